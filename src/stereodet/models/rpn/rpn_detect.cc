#include "stereodet/models/rpn/rpn_detect.h"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "stereodet/kitti/label_io.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/rpn/rpn_data.h"
#include "stereodet/models/ssd.h"
#include "stereodet/models/ssd_detect.h"
#include "stereodet/stereo/degradation.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

void DetectRpnOptions::Check() const {
  detect.Check();
  STEREODET_CHECK(!model_dir.empty()) << "--model is required";
  STEREODET_CHECK(!data_root.empty()) << "--data is required";
  STEREODET_CHECK(!out_dir.empty()) << "--out is required";
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
  STEREODET_CHECK(batch_size >= 1) << "batch size must be >= 1, got " << batch_size;
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
  STEREODET_CHECK(max_frames >= 0) << "max_frames must be >= 0, got " << max_frames;
  shard.Check();
  STEREODET_CHECK(ParseComputeDevice(device).has_value())
      << "unknown device '" << device << "' (expected cpu or cuda)";
}

DetectRpnSummary DetectRpn(const DetectRpnOptions& options) {
  options.Check();
  const ComputeDevice device = ResolveComputeDevice(options.device);
  const Timer timer;
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir,
                                  {{"--data", options.data_root / options.subset},
                                   {"--data", options.data_root / "ImageSets"},
                                   {"--model", options.model_dir}});
  StagedFolder out(options.out_dir, "detect rpn", DetectionFolderMakers());
  SetTorchThreads(options.threads);
  const RpnModel model = RpnModel::Load(options.model_dir, device);
  const RpnConfig& config = model.config();
  const bool geometry = config.input == RpnInput::kRgbd;

  const KittiDataset dataset(options.data_root, options.subset);
  const std::vector<std::string> all_ids =
      DetectFrameList(dataset, options.split, options.max_frames);
  // A shard: whole batches of the list (detect_shard.h), nothing in the loop below.
  const std::vector<std::string> ids = ShardFrames(all_ids, options.shard, options.batch_size);
  RequiredFiles required;
  required.image_left = true;
  required.image_right = required.calib = geometry;
  const std::vector<std::string> missing = FindMissingFiles(dataset, ids, required);
  if (!missing.empty()) {
    STEREODET_THROW_IO() << missing.size() << " required files are missing under "
                         << dataset.SubsetDir().string() << ", e.g. " << missing.front();
  }
  StereoOptions stereo = model.stereo();
  stereo.blur.sigma_px = options.blur_sigma_px;
  stereo.blur.mode = BlurMode::kNetworkImage;

  DetectRpnSummary summary;
  StageTimes times;
  ProgressReporter progress("detect", static_cast<int64_t>(ids.size()), options.progress);
  for (size_t begin = 0; begin < ids.size(); begin += options.batch_size) {
    const size_t end = std::min(ids.size(), begin + options.batch_size);
    const size_t n = end - begin;
    std::vector<PlanarImage> inputs(n);
    std::vector<cv::Size> sizes(n);
    ParallelFor(
        n,
        [&](size_t i) {
          const FramePaths paths = dataset.Paths(ids[begin + i]);
          if (geometry) {
            RpnGeometry g;
            {
              ScopedStage stage(times, "stereo");
              g = ComputeRpnGeometry(paths, stereo);  // blurs the network's image only
            }
            sizes[i] = g.network_image.size();
            ScopedStage stage(times, "encode");
            inputs[i] =
                PrepareRpnInput(g.network_image, g.depth_code, g.height_code, config, stereo.depth);
            return;
          }
          cv::Mat image;
          {
            ScopedStage stage(times, "read");
            image = ReadColourImage(paths.image_left);
          }
          sizes[i] = image.size();
          if (options.blur_sigma_px > 0.0) {
            ScopedStage stage(times, "blur");
            image = GaussianBlurImage(image, options.blur_sigma_px);
          }
          ScopedStage stage(times, "encode");
          inputs[i] = PrepareRpnInput(image, {}, {}, config);
        },
        options.threads);
    std::vector<std::vector<ScoredBox>> boxes;
    {
      ScopedStage stage(times, "network");
      boxes = model.Detect(inputs, options.detect);
    }
    ScopedStage stage(times, "write");
    for (size_t i = 0; i < n; ++i) {
      const double sx = static_cast<double>(sizes[i].width) / config.input_width;
      const double sy = static_cast<double>(sizes[i].height) / config.input_height;
      const std::vector<Object> objects =
          ToKittiDetections(boxes[i], config.classes, sx, sy, sizes[i].width, sizes[i].height);
      WriteObjects(out.path() / (ids[begin + i] + ".txt"), objects);
      summary.detections += static_cast<int64_t>(objects.size());
    }
    progress.Add(static_cast<int64_t>(n));
  }
  progress.Finish();

  RunManifest manifest;
  manifest.tool = "detect rpn";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"model", options.model_dir.string()},
                     {"data", options.data_root.string()},
                     {"subset", options.subset},
                     {"split", options.split}};
  manifest.settings_json = fmt::format(
      R"({{"model_weights_fnv1a64": "{}", "input": "{}", "blur_sigma_px": {}, )"
      R"("score_threshold": {}, "nms_iou_threshold": {}, "max_detections": {}, )"
      R"("proposals_before_nms": {}, "proposals": {}, "max_frames": {}, "device": "{}"}})",
      HashFileHex(options.model_dir / "model.pt"), RpnInputName(config.input),
      options.blur_sigma_px, options.detect.decode.score_threshold,
      options.detect.decode.nms.iou_threshold, options.detect.decode.nms.max_detections,
      options.detect.proposals.pre_nms_top_n, options.detect.proposals.post_nms_top_n,
      options.max_frames, options.device);
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, options.shard, options.batch_size);
  summary.frames = static_cast<int>(ids.size());
  summary.seconds = timer.ElapsedSeconds();
  summary.images_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.stage_times = times.Format();
  return summary;
}

}  // namespace stereodet
