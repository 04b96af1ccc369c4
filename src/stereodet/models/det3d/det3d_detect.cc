#include "stereodet/models/det3d/det3d_detect.h"

#include <fmt/format.h>

#include <utility>

#include "stereodet/kitti/label_io.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

void DetectDet3dOptions::Check() const {
  decode.Check();
  filter.Check();
  STEREODET_CHECK(!model_dir.empty()) << "--model is required";
  STEREODET_CHECK(!data_root.empty()) << "--data is required";
  STEREODET_CHECK(!out_dir.empty()) << "--out is required";
  STEREODET_CHECK(batch_size >= 1) << "batch size must be >= 1, got " << batch_size;
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
  STEREODET_CHECK(max_frames >= 0) << "max_frames must be >= 0, got " << max_frames;
  shard.Check();
  STEREODET_CHECK(ParseComputeDevice(device).has_value())
      << "unknown device '" << device << "' (expected cpu or cuda)";
}

DetectDet3dSummary DetectDet3d(const DetectDet3dOptions& options) {
  options.Check();
  const ComputeDevice device = ResolveComputeDevice(options.device);
  const Timer timer;
  std::vector<std::pair<std::string, std::filesystem::path>> inputs = {
      {"--data", options.data_root / options.subset},
      {"--data", options.data_root / "ImageSets"},
      {"--model", options.model_dir}};
  if (!options.points_dir.empty()) inputs.push_back({"--points", options.points_dir});
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir, inputs);
  StagedFolder out(options.out_dir, "detect det3d", DetectionFolderMakers());
  SetTorchThreads(options.threads);
  const Det3dModel model = Det3dModel::Load(options.model_dir, device);
  const Det3dConfig& config = model.config();
  STEREODET_CHECK(config.input != PointSource::kStereo || !options.points_dir.empty())
      << options.model_dir.string()
      << " is a stereo model: --points must name the `stereodet stereo --encode points` folder";

  const KittiDataset dataset(options.data_root, options.subset);
  const std::vector<std::string> all_ids =
      DetectFrameList(dataset, options.split, options.max_frames);
  const std::vector<std::string> ids =
      ShardFrames(all_ids, options.shard, options.batch_size);  // detect_shard.h
  DetectDet3dSummary summary;
  ProgressReporter progress("detect", static_cast<int64_t>(ids.size()), options.progress);
  for (size_t begin = 0; begin < ids.size(); begin += options.batch_size) {
    const size_t end = std::min(ids.size(), begin + options.batch_size);
    std::vector<Det3dFrame> frames(end - begin);
    std::vector<Det3dSample> samples(end - begin);
    ParallelFor(
        frames.size(),
        [&](size_t i) {
          frames[i] = LoadDet3dFrame(dataset, options.points_dir, config.input, ids[begin + i],
                                     config.classes, config.grid, options.filter,
                                     /*with_labels=*/false);
          samples[i] = MakeDet3dSample(frames[i], config, model.anchors(), false);
        },
        options.threads);
    const Timer network_timer;
    const std::vector<std::vector<ScoredLidarBox>> boxes = model.Detect(samples, options.decode);
    summary.network_seconds += network_timer.ElapsedSeconds();
    for (size_t i = 0; i < frames.size(); ++i) {
      std::vector<Object> objects;
      for (const ScoredLidarBox& b : boxes[i]) {
        std::optional<Object> o = ToKitti3DDetection(b, config.classes, frames[i].calib,
                                                     frames[i].image_width, frames[i].image_height);
        if (o) objects.push_back(*o);
      }
      WriteObjects(out.path() / (frames[i].id + ".txt"), objects);
      summary.detections += static_cast<int64_t>(objects.size());
    }
    progress.Add(static_cast<int64_t>(frames.size()));
  }
  progress.Finish();

  RunManifest manifest;
  manifest.tool = "detect det3d";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"model", options.model_dir.string()},
                     {"data", options.data_root.string()},
                     {"subset", options.subset},
                     {"split", options.split}};
  if (!options.points_dir.empty())
    manifest.inputs.push_back({"points", options.points_dir.string()});
  manifest.settings_json = fmt::format(
      R"({{"model_weights_fnv1a64": "{}", "input": "{}", "score_threshold": {}, )"
      R"("nms_iou_threshold": {}, "max_detections": {}, "max_frames": {}, "device": "{}", )"
      R"("stereo_max_distance_m": {}, "camera_fov_only": {}}})",
      HashFileHex(options.model_dir / "model.pt"), PointSourceName(config.input),
      options.decode.score_threshold, options.decode.nms.iou_threshold,
      options.decode.nms.max_detections, options.max_frames, options.device,
      options.filter.stereo_max_distance_m, options.filter.camera_fov_only);
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, options.shard, options.batch_size);
  summary.frames = static_cast<int>(ids.size());
  summary.seconds = timer.ElapsedSeconds();
  summary.frames_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  return summary;
}

}  // namespace stereodet
