#include "stereodet/models/ssd_detect.h"

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
#include "stereodet/models/ssd.h"
#include "stereodet/models/ssd_data.h"
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

std::vector<Object> ToKittiDetections(const std::vector<ScoredBox>& boxes,
                                      const std::vector<std::string>& classes, double scale_x,
                                      double scale_y, int image_width, int image_height) {
  std::vector<Object> objects;
  for (const ScoredBox& b : boxes) {
    STEREODET_CHECK(b.label >= 1 && b.label <= static_cast<int>(classes.size()))
        << "detection label " << b.label << " out of range";
    Object o;
    o.type = classes[b.label - 1];
    o.truncated = -1.0;
    o.occluded = -1;
    // Rounded to 0.01 px (KITTI's own precision; the files stay short and read back exactly).
    auto px = [](double v, double hi) {
      return std::round(std::clamp(v, 0.0, hi) * 100.0) / 100.0;
    };
    o.box = {px(b.box.left * scale_x, image_width), px(b.box.top * scale_y, image_height),
             px(b.box.right * scale_x, image_width), px(b.box.bottom * scale_y, image_height)};
    if (o.box.Width() <= 0.0 || o.box.Height() <= 0.0) continue;
    o.SetNot3DEstimated();
    // Six decimals keep the ranking of all but near-identical scores.
    o.score = std::round(static_cast<double>(b.score) * 1e6) / 1e6;
    objects.push_back(o);
  }
  return objects;
}

void RunTwoStagePipeline(int num_batches, bool overlap, const std::function<void(int)>& prepare,
                         const std::function<void(int)>& consume) {
  if (!overlap) {
    for (int k = 0; k < num_batches; ++k) {
      prepare(k);
      consume(k);
    }
    return;
  }
  if (num_batches <= 0) return;
  prepare(0);
  for (int k = 0; k < num_batches; ++k) {
    // A thread per batch: the batches are large (the network's batch of frames), so starting one
    // costs nothing next to them, and std::async's future rethrows the preparation's exception.
    std::future<void> next;
    if (k + 1 < num_batches) next = std::async(std::launch::async, prepare, k + 1);
    try {
      consume(k);
    } catch (...) {
      if (next.valid()) next.wait();  // the preparation uses the caller's state: let it finish
      throw;
    }
    if (next.valid()) next.get();
  }
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
  const std::vector<std::string> missing = FindMissingFiles(dataset, ids, required);
  if (!missing.empty()) {
    STEREODET_THROW_IO() << missing.size() << " required files are missing under "
                         << dataset.SubsetDir().string() << ", e.g. " << missing.front();
  }

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
            frame.right = ReadColourImage(paths.image_right);
            CheckStereoPairSize(frame.left, frame.right, paths.image_left, paths.image_right);
            CheckImageFitsMatcher(stereo->disparity, frame.left.size(), paths.image_left);
            frame.calib = ReadCalibration(paths.calib);
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

  RunManifest manifest;
  manifest.tool = "detect ssd";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"model", options.model_dir.string()},
                     {"data", options.data_root.string()},
                     {"subset", options.subset},
                     {"split", options.split}};
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
