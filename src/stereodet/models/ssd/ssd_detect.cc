#include "stereodet/models/ssd/ssd_detect.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <future>
#include <opencv2/imgcodecs.hpp>
#include <utility>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/detector.h"
#include "stereodet/models/ssd/ssd_data.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/stereo/dataset_encoder.h"
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

void DetectSsdOptions::Check() const {
  decode.Check();
  if (stereo) stereo->Check();
  CheckDetectionRun(*this);
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
}

std::optional<StereoOptions> ModelStereoSettings(const std::filesystem::path& model_dir) {
  const std::filesystem::path config_path = model_dir / "model.json";
  const std::string text = ReadFile(config_path);
  if (!UsesHeight(SsdConfigFromJson(text, config_path.string()).encoding)) return std::nullopt;
  return ReadStereoRecord(text, config_path.string());
}

std::string StereoMismatch(const DetectSsdOptions& options) {
  if (!options.stereo) return "";
  const std::optional<StereoOptions> recorded = ModelStereoSettings(options.model_dir);
  if (!recorded) return "";
  return DifferingStereoSettings(*recorded, *options.stereo);
}

DetectSsdSummary DetectSsd(const DetectSsdOptions& options) {
  options.Check();
  const Timer timer;
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir,
                                  {{"--data", options.data_root / options.subset},
                                   {"--data", options.data_root / "ImageSets"},
                                   {"--model", options.model_dir},
                                   {"--stereo", options.stereo_dir}});
  // Refuse a folder of something else before the work, not after it.
  StagedFolder out(options.out_dir, "detect ssd", DetectionFolderMakers());
  DetectorOptions detector_options;
  detector_options.device = options.device;
  detector_options.threads = options.threads;
  detector_options.blur_sigma_px = options.blur_sigma_px;
  detector_options.stereo = options.stereo;
  detector_options.ssd = options.decode;
  Detector detector = OpenDetectorOfFamily(options.model_dir, detector_options, "ssd");
  // The settings the heights are made with (the model's or the flags', with the blur).
  const std::optional<StereoOptions> stereo = detector.stereo();
  const bool height = stereo.has_value();

  const KittiDataset dataset(options.data_root, options.subset);
  const std::vector<std::string> all_ids =
      DetectFrameList(dataset, options.split, options.max_frames);
  // A shard is a choice of frames and a record beside them, nothing in the loop below.
  const std::vector<std::string> ids = ShardFrames(all_ids, options.shard, options.batch_size);
  RequiredFiles required;
  required.image_left = true;
  const bool from_folder = height && !options.stereo_dir.empty();
  required.image_right = required.calib = height && !from_folder;
  CheckRequiredFiles(dataset, ids, required);

  std::optional<StereoFolderRecord> folder;
  if (from_folder) {
    folder = ReadStereoFolder(options.stereo_dir);
    CheckStereoFolderData(*folder, dataset);
    std::string differ = DifferingStereoSettings(*stereo, folder->stereo);
    for (size_t at; (at = differ.find("(requested: ")) != std::string::npos;) {
      differ.replace(at, 12, "(stereo.json: ");
    }
    STEREODET_CHECK(differ.empty())
        << "--stereo " << options.stereo_dir.string() << ": its stereo.json records other stereo "
        << "settings than " << (options.stereo ? "the stereo flags" : "the model's model.json")
        << ": " << differ << "; use a stereo folder made with the model's settings, or no --stereo";
  }

  DetectSsdSummary summary;
  StageTimes times;
  ProgressReporter progress("detect", static_cast<int64_t>(ids.size()), options.progress);
  // One batch of frames read and prepared for the network (Detector::Prepare: stereo, encoding);
  // two slots, so that batch k + 1 can be prepared while the network runs on batch k.
  std::unique_ptr<Detector::PreparedBatch> slots[2];
  const size_t batch_size = static_cast<size_t>(options.batch_size);
  const int num_batches = static_cast<int>((ids.size() + batch_size - 1) / batch_size);
  auto prepare = [&](int k) {
    const size_t begin = static_cast<size_t>(k) * batch_size;
    const size_t n = std::min(ids.size(), begin + batch_size) - begin;
    std::vector<StereoFrame> frames(n);
    ParallelFor(
        n,
        [&](size_t i) {
          const std::string& id = ids[begin + i];
          const FramePaths paths = dataset.Paths(id);
          StereoFrame& frame = frames[i];
          frame.id = id;
          ScopedStage stage(times, "read");
          frame.left = ReadColourImage(paths.image_left);
          if (from_folder) {
            // At the match size, as matching in line gives them: the folder's full-resolution
            // codes resized to the network would differ.
            frame.height_code = ReadStereoFolderHeightAtMatchScale(*folder, id);
          } else if (height) {
            ReadStereoPairFiles(paths, stereo->disparity, frame);
          }
        },
        options.threads);
    if (from_folder) {
      for (const StereoFrame& frame : frames) {
        const cv::Size match = stereo->disparity.MatchSize(frame.left.size());
        STEREODET_CHECK_IO(frame.height_code.size() == match)
            << "--stereo " << options.stereo_dir.string() << ": the heights of frame " << frame.id
            << " are " << frame.height_code.cols << "x" << frame.height_code.rows
            << " px at the match scale, " << match.width << "x" << match.height
            << " for its left image of " << frame.left.cols << "x" << frame.left.rows;
      }
    }
    slots[k % 2] = detector.Prepare(frames);
  };
  auto consume = [&](int k) {
    const std::vector<DetectResult> results = detector.Run(std::move(slots[k % 2]));
    ScopedStage stage(times, "write");
    summary.detections += WriteDetectResults(results, out.path(), times);
    progress.Add(static_cast<int64_t>(results.size()));
  };
  RunTwoStagePipeline(num_batches, options.pipeline, prepare, consume);
  progress.Finish();

  RunManifest manifest = DetectionManifest("detect ssd", options.command_line, options.model_dir,
                                           options.data_root, options.subset, options.split);
  if (from_folder) manifest.inputs.emplace_back("stereo", options.stereo_dir.string());
  manifest.settings_json = fmt::format(
      R"({{"model_weights_fnv1a64": "{}", "encoding": "{}", "blur_sigma_px": {}, )"
      R"("score_threshold": {}, "nms_iou_threshold": {}, "max_detections": {}, "max_frames": {}{}}})",
      HashFileHex(options.model_dir / "model.pt"), detector.input(), options.blur_sigma_px,
      options.decode.score_threshold, options.decode.nms.iou_threshold,
      options.decode.nms.max_detections, options.max_frames,
      // The stereo settings the heights were made with (RGB-H only): the model's, or the flags'.
      height ? ", \"stereo\": " + StereoSettingsJson(*stereo) : std::string());
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, options.shard, options.batch_size);
  summary.frames = static_cast<int>(ids.size());
  summary.seconds = timer.ElapsedSeconds();
  summary.images_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.stage_times = times.Format();
  return summary;
}

}  // namespace stereodet
