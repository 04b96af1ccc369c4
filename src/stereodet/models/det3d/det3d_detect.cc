#include "stereodet/models/det3d/det3d_detect.h"

#include <fmt/format.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/det3d/det3d_data.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/detector.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

void DetectDet3dOptions::Check() const {
  decode.Check();
  filter.Check();
  DetectionRunOptions::Check();
}

DetectSummary DetectDet3d(const DetectDet3dOptions& options) {
  options.Check();
  DetectorOptions detector_options;
  detector_options.det3d = options.decode;
  detector_options.det3d_points = options.filter;
  std::vector<std::pair<std::string, std::filesystem::path>> more_inputs;
  if (!options.points_dir.empty()) more_inputs.emplace_back("--points", options.points_dir);
  DetectionRun run(options, "det3d", detector_options, more_inputs);
  const PointSource source = *ParsePointSource(run.detector.input());
  STEREODET_CHECK(source != PointSource::kStereo || !options.points_dir.empty())
      << options.model_dir.string()
      << " is a stereo model: --points must name the `stereodet stereo --encode points` folder";

  run.DetectFrames(
      [&](const std::string& id, StereoFrame& frame) {
        // The calibration, the image's size (its PNG header: nothing decoded) and the points.
        const FramePaths paths = run.dataset.Paths(id);
        frame.calib = ReadCalibration(paths.calib);
        const auto [width, height] = PngImageSize(paths.image_left);
        frame.image_size = cv::Size(width, height);
        frame.points = ReadVelodyne(PointsPath(run.dataset, options.points_dir, source, id));
      },
      /*overlap=*/true);
  std::vector<std::pair<std::string, std::string>> manifest_inputs;
  if (!options.points_dir.empty())
    manifest_inputs.emplace_back("points", options.points_dir.string());
  return run.Commit(
      manifest_inputs,
      fmt::format(R"("input": "{}", "score_threshold": {}, "nms_iou_threshold": {}, )"
                  R"("max_detections": {}, "max_frames": {}, "device": "{}", )"
                  R"("stereo_max_distance_m": {}, "camera_fov_only": {})",
                  run.detector.input(), options.decode.score_threshold,
                  options.decode.nms.iou_threshold, options.decode.nms.max_detections,
                  options.max_frames, options.device, options.filter.stereo_max_distance_m,
                  options.filter.camera_fov_only));
}

}  // namespace stereodet
