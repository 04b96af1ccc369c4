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
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

void DetectRpnOptions::Check() const {
  detect.Check();
  DetectionRunOptions::Check();
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
}

DetectSummary DetectRpn(const DetectRpnOptions& options) {
  options.Check();
  DetectorOptions detector_options;
  detector_options.blur_sigma_px = options.blur_sigma_px;
  detector_options.rpn = options.detect;
  DetectionRun run(options, "rpn", detector_options);
  const bool geometry = run.detector.needs().right_image;
  RequiredFiles required;
  required.image_left = true;
  required.image_right = required.calib = geometry;
  CheckRequiredFiles(run.dataset, run.ids, required);

  run.DetectFrames(
      [&](const std::string& id, StereoFrame& frame) {
        const FramePaths paths = run.dataset.Paths(id);
        frame.left = ReadColourImage(paths.image_left);
        if (geometry) ReadStereoPairFiles(paths, run.detector.stereo()->disparity, frame);
      },
      /*overlap=*/true);
  return run.Commit(
      {},
      fmt::format(R"("input": "{}", "blur_sigma_px": {}, "score_threshold": {}, )"
                  R"("nms_iou_threshold": {}, "max_detections": {}, )"
                  R"("proposals_before_nms": {}, "proposals": {}, "max_frames": {}, )"
                  R"("device": "{}")",
                  run.detector.input(), options.blur_sigma_px,
                  options.detect.decode.score_threshold, options.detect.decode.nms.iou_threshold,
                  options.detect.decode.nms.max_detections, options.detect.proposals.pre_nms_top_n,
                  options.detect.proposals.post_nms_top_n, options.max_frames, options.device));
}

}  // namespace stereodet
