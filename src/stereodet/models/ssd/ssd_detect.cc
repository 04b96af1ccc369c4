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
#include "stereodet/models/model_json.h"
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
  DetectionRunOptions::Check();
  STEREODET_CHECK(blur_sigma_px >= 0.0 && std::isfinite(blur_sigma_px))
      << "blur sigma must be >= 0, got " << blur_sigma_px;
}

std::optional<StereoOptions> ModelStereoSettings(const std::filesystem::path& model_dir) {
  const std::filesystem::path config_path = model_dir / kModelConfigFile;
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

DetectSummary DetectSsd(const DetectSsdOptions& options) {
  options.Check();
  DetectorOptions detector_options;
  detector_options.blur_sigma_px = options.blur_sigma_px;
  detector_options.stereo = options.stereo;
  detector_options.ssd = options.decode;
  DetectionRun run(options, "ssd", detector_options, {{"--stereo", options.stereo_dir}});
  // The settings the heights are made with (the model's or the flags', with the blur).
  const std::optional<StereoOptions> stereo = run.detector.stereo();
  const bool height = stereo.has_value();
  RequiredFiles required;
  required.image_left = true;
  const bool from_folder = height && !options.stereo_dir.empty();
  required.image_right = required.calib = height && !from_folder;
  CheckRequiredFiles(run.dataset, run.ids, required);

  std::optional<StereoFolderRecord> folder;
  if (from_folder) {
    folder = ReadStereoFolder(options.stereo_dir);
    CheckStereoFolderData(*folder, run.dataset);
    std::string differ = DifferingStereoSettings(*stereo, folder->stereo);
    for (size_t at; (at = differ.find("(requested: ")) != std::string::npos;) {
      differ.replace(at, 12, "(stereo.json: ");
    }
    // The exact command that makes a folder this run can use: the model's settings file, with
    // the stereo flags of this run repeated when it has any.
    const std::string make_folder = fmt::format(
        "stereodet stereo --data {} --subset {} --split {} --encode rgbh --stereo-settings {}{} "
        "--out NEW_FOLDER",
        options.data_root.string(), options.subset, options.split,
        (options.model_dir / "model.json").string(),
        options.stereo ? " plus this run's stereo flags" : "");
    STEREODET_CHECK(differ.empty())
        << "--stereo " << options.stereo_dir.string() << ": its stereo.json records other stereo "
        << "settings than " << (options.stereo ? "the stereo flags" : "the model's model.json")
        << ": " << differ << "; make a folder with them (`" << make_folder
        << "`) and pass it to --stereo, or leave out --stereo";
  }

  run.DetectFrames(
      [&](const std::string& id, StereoFrame& frame) {
        const FramePaths paths = run.dataset.Paths(id);
        frame.left = ReadColourImage(paths.image_left);
        if (from_folder) {
          // At the match size, as matching in line gives them: the folder's full-resolution
          // codes resized to the network would differ.
          frame.height_code = ReadStereoFolderHeightAtMatchScale(*folder, id);
          const cv::Size match = stereo->disparity.MatchSize(frame.left.size());
          STEREODET_CHECK_IO(frame.height_code.size() == match)
              << "--stereo " << options.stereo_dir.string() << ": the heights of frame " << id
              << " are " << frame.height_code.cols << "x" << frame.height_code.rows
              << " px at the match scale, " << match.width << "x" << match.height
              << " for its left image of " << frame.left.cols << "x" << frame.left.rows;
        } else if (height) {
          ReadStereoPairFiles(paths, stereo->disparity, frame);
        }
      },
      options.pipeline);
  std::vector<std::pair<std::string, std::string>> manifest_inputs;
  if (from_folder) manifest_inputs.emplace_back("stereo", options.stereo_dir.string());
  return run.Commit(
      manifest_inputs,
      fmt::format(R"("encoding": "{}", "blur_sigma_px": {}, "score_threshold": {}, )"
                  R"("nms_iou_threshold": {}, "max_detections": {}, "max_frames": {}{})",
                  run.detector.input(), options.blur_sigma_px, options.decode.score_threshold,
                  options.decode.nms.iou_threshold, options.decode.nms.max_detections,
                  options.max_frames,
                  // The stereo settings the heights were made with (RGB-H only): the
                  // model's, or the flags'.
                  height ? ", \"stereo\": " + StereoSettingsJson(*stereo) : std::string()));
}

}  // namespace stereodet
