#include "stereodet/models/det3d/det3d_detect.h"

#include <fmt/format.h>

#include <utility>

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
  CheckDetectionRun(*this);
}

DetectDet3dSummary DetectDet3d(const DetectDet3dOptions& options) {
  options.Check();
  const Timer timer;
  std::vector<std::pair<std::string, std::filesystem::path>> inputs = {
      {"--data", options.data_root / options.subset},
      {"--data", options.data_root / "ImageSets"},
      {"--model", options.model_dir}};
  if (!options.points_dir.empty()) inputs.push_back({"--points", options.points_dir});
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir, inputs);
  StagedFolder out(options.out_dir, "detect det3d", DetectionFolderMakers());
  DetectorOptions detector_options;
  detector_options.device = options.device;
  detector_options.threads = options.threads;
  detector_options.det3d = options.decode;
  detector_options.det3d_points = options.filter;
  Detector detector = OpenDetectorOfFamily(options.model_dir, detector_options, "det3d");
  const PointSource source = *ParsePointSource(detector.input());
  STEREODET_CHECK(source != PointSource::kStereo || !options.points_dir.empty())
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
    const size_t n = std::min(ids.size(), begin + options.batch_size) - begin;
    std::vector<StereoFrame> frames(n);
    ParallelFor(
        n,
        [&](size_t i) {
          // The calibration, the image's size (its PNG header: nothing decoded) and the points.
          const std::string& id = ids[begin + i];
          const FramePaths paths = dataset.Paths(id);
          StereoFrame& frame = frames[i];
          frame.id = id;
          frame.calib = ReadCalibration(paths.calib);
          const auto [width, height] = PngImageSize(paths.image_left);
          frame.image_size = cv::Size(width, height);
          frame.points = ReadVelodyne(PointsPath(dataset, options.points_dir, source, id));
        },
        options.threads);
    const std::vector<DetectResult> results = detector.DetectBatch(frames);
    for (const DetectResult& r : results) {
      summary.network_seconds += r.times.network_s;
      WriteObjects(out.path() / (r.id + ".txt"), r.objects);
      summary.detections += static_cast<int64_t>(r.objects.size());
    }
    progress.Add(static_cast<int64_t>(n));
  }
  progress.Finish();

  RunManifest manifest = DetectionManifest("detect det3d", options.command_line, options.model_dir,
                                           options.data_root, options.subset, options.split);
  if (!options.points_dir.empty())
    manifest.inputs.push_back({"points", options.points_dir.string()});
  manifest.settings_json = fmt::format(
      R"({{"model_weights_fnv1a64": "{}", "input": "{}", "score_threshold": {}, )"
      R"("nms_iou_threshold": {}, "max_detections": {}, "max_frames": {}, "device": "{}", )"
      R"("stereo_max_distance_m": {}, "camera_fov_only": {}}})",
      HashFileHex(options.model_dir / "model.pt"), detector.input(), options.decode.score_threshold,
      options.decode.nms.iou_threshold, options.decode.nms.max_detections, options.max_frames,
      options.device, options.filter.stereo_max_distance_m, options.filter.camera_fov_only);
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, options.shard, options.batch_size);
  summary.frames = static_cast<int>(ids.size());
  summary.seconds = timer.ElapsedSeconds();
  summary.frames_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  return summary;
}

}  // namespace stereodet
