#include "stereodet/models/rpn/rpn_detect.h"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/detector.h"
#include "stereodet/models/rpn/rpn_data.h"
#include "stereodet/stereo/degradation.h"
#include "stereodet/stereo/disparity.h"
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
  CheckDetectionRun(*this);
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
}

DetectRpnSummary DetectRpn(const DetectRpnOptions& options) {
  options.Check();
  const Timer timer;
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir,
                                  {{"--data", options.data_root / options.subset},
                                   {"--data", options.data_root / "ImageSets"},
                                   {"--model", options.model_dir}});
  StagedFolder out(options.out_dir, "detect rpn", DetectionFolderMakers());
  DetectorOptions detector_options;
  detector_options.device = options.device;
  detector_options.threads = options.threads;
  detector_options.blur_sigma_px = options.blur_sigma_px;
  detector_options.rpn = options.detect;
  Detector detector = OpenDetectorOfFamily(options.model_dir, detector_options, "rpn");
  const bool geometry = detector.needs().right_image;

  const KittiDataset dataset(options.data_root, options.subset);
  const std::vector<std::string> all_ids =
      DetectFrameList(dataset, options.split, options.max_frames);
  // A shard: whole batches of the list (detect_shard.h), nothing in the loop below.
  const std::vector<std::string> ids = ShardFrames(all_ids, options.shard, options.batch_size);
  RequiredFiles required;
  required.image_left = true;
  required.image_right = required.calib = geometry;
  CheckRequiredFiles(dataset, ids, required);

  DetectRpnSummary summary;
  StageTimes times;
  ProgressReporter progress("detect", static_cast<int64_t>(ids.size()), options.progress);
  for (size_t begin = 0; begin < ids.size(); begin += options.batch_size) {
    const size_t n = std::min(ids.size(), begin + options.batch_size) - begin;
    std::vector<StereoFrame> frames(n);
    ParallelFor(
        n,
        [&](size_t i) {
          const FramePaths paths = dataset.Paths(ids[begin + i]);
          StereoFrame& frame = frames[i];
          frame.id = ids[begin + i];
          ScopedStage stage(times, "read");
          frame.left = ReadColourImage(paths.image_left);
          if (geometry) ReadStereoPairFiles(paths, detector.stereo()->disparity, frame);
        },
        options.threads);
    const std::vector<DetectResult> results = detector.DetectBatch(frames);
    ScopedStage stage(times, "write");
    summary.detections += WriteDetectResults(results, out.path(), times);
    progress.Add(static_cast<int64_t>(n));
  }
  progress.Finish();

  RunManifest manifest = DetectionManifest("detect rpn", options.command_line, options.model_dir,
                                           options.data_root, options.subset, options.split);
  manifest.settings_json = fmt::format(
      R"({{"model_weights_fnv1a64": "{}", "input": "{}", "blur_sigma_px": {}, )"
      R"("score_threshold": {}, "nms_iou_threshold": {}, "max_detections": {}, )"
      R"("proposals_before_nms": {}, "proposals": {}, "max_frames": {}, "device": "{}"}})",
      HashFileHex(options.model_dir / "model.pt"), detector.input(), options.blur_sigma_px,
      options.detect.decode.score_threshold, options.detect.decode.nms.iou_threshold,
      options.detect.decode.nms.max_detections, options.detect.proposals.pre_nms_top_n,
      options.detect.proposals.post_nms_top_n, options.max_frames, options.device);
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, options.shard, options.batch_size);
  summary.frames = static_cast<int>(ids.size());
  summary.seconds = timer.ElapsedSeconds();
  summary.images_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.stage_times = times.Format();
  return summary;
}

}  // namespace stereodet
