#include "stereodet/stereo/dataset_encoder.h"

#include <fmt/format.h>

#include <atomic>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// The files one frame produces under OUT.
struct FrameOutputs {
  fs::path rgbh, depth, height, image, points, disparity, ground;
};

FrameOutputs OutputPaths(const fs::path& out, const std::string& id) {
  return {out / "rgbh" / (id + ".png"),     out / "depth" / (id + ".png"),
          out / "height" / (id + ".png"),   out / "image_2" / (id + ".png"),
          out / "velodyne" / (id + ".bin"), out / "disparity" / (id + ".png"),
          out / "ground" / (id + ".txt")};
}

std::vector<fs::path> RequiredPaths(const FrameOutputs& paths, const DatasetOutputs& outputs,
                                    bool blurred) {
  std::vector<fs::path> required = {paths.ground};
  if (outputs.rgbh) required.push_back(paths.rgbh);
  if (outputs.rgbd) {
    required.push_back(paths.depth);
    required.push_back(paths.height);
    if (blurred) required.push_back(paths.image);
  }
  if (outputs.points) required.push_back(paths.points);
  if (outputs.disparity) required.push_back(paths.disparity);
  return required;
}

// "a.b: V" for every leaf of a JSON object, in key order.
void Flatten(const nlohmann::json& j, const std::string& prefix,
             std::map<std::string, std::string>& out) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      Flatten(value, prefix.empty() ? key : prefix + "." + key, out);
    }
  } else {
    out[prefix] = j.dump();
  }
}

// The settings of two manifests that differ, "key: OLD (this run: NEW)", joined by "; "; the
// outputs
// ("encode") are left out. Empty when only the outputs differ (or nothing).
std::string DifferingSettings(const std::string& old_text, const std::string& new_text,
                              const fs::path& source) {
  nlohmann::json old_json;
  try {
    old_json = nlohmann::json::parse(old_text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source.string(), 0, "", std::string("not valid JSON: ") + e.what());
  }
  std::map<std::string, std::string> before, now;
  Flatten(old_json, "", before);
  Flatten(nlohmann::json::parse(new_text), "", now);
  std::string differences;
  auto add = [&differences](const std::string& key, const std::string& old_value,
                            const std::string& new_value) {
    if (!differences.empty()) differences += "; ";
    differences += key + ": " + old_value + " (this run: " + new_value + ")";
  };
  for (const auto& [key, value] : now) {
    if (key == "encode") continue;
    const auto it = before.find(key);
    if (it == before.end()) {
      add(key, "not recorded", value);
    } else if (it->second != value) {
      add(key, it->second, value);
    }
  }
  for (const auto& [key, value] : before) {
    if (key != "encode" && !now.count(key)) add(key, value, "not a setting");
  }
  return differences;
}

// The union of the outputs named in an old manifest's "encode" and `outputs`.
DatasetOutputs UnionOutputs(const std::string& old_text, DatasetOutputs outputs) {
  const nlohmann::json j = nlohmann::json::parse(old_text);
  if (!j.contains("encode") || !j["encode"].is_string()) return outputs;
  const std::string encode = j["encode"].get<std::string>();
  if (encode.empty()) return outputs;
  const DatasetOutputs old = ParseDatasetOutputs(encode);
  outputs.rgbh = outputs.rgbh || old.rgbh;
  outputs.rgbd = outputs.rgbd || old.rgbd;
  outputs.points = outputs.points || old.points;
  outputs.disparity = outputs.disparity || old.disparity;
  return outputs;
}

// The hash ground/ID.txt records ("settings HASH" line), or empty when it has none or is missing.
std::string RecordedFrameHash(const fs::path& ground) {
  std::error_code ec;
  if (!fs::exists(ground, ec)) return {};
  const std::string text = ReadFile(ground);
  const std::string key = "\nsettings ";
  const size_t at = text.find(key);
  if (at == std::string::npos) return {};
  const size_t begin = at + key.size();
  return text.substr(begin, text.find('\n', begin) - begin);
}

constexpr const char* kGroundFileHeader =
    "# ground plane in the rect frame: n . X + offset = 0, n up; fitted 1 = RANSAC fit used, 0 = "
    "nominal fallback\n";

}  // namespace

std::string DatasetOutputsName(const DatasetOutputs& outputs) {
  std::string name;
  auto add = [&name](bool chosen, const char* output) {
    if (!chosen) return;
    if (!name.empty()) name += ',';
    name += output;
  };
  add(outputs.rgbh, "rgbh");
  add(outputs.rgbd, "rgbd");
  add(outputs.points, "points");
  add(outputs.disparity, "disparity");
  return name;
}

DatasetOutputs ParseDatasetOutputs(std::string_view text) {
  DatasetOutputs outputs;
  outputs.rgbh = false;
  for (std::string_view token : Split(text, ',')) {
    token = Trim(token);
    if (token == "rgbh") {
      outputs.rgbh = true;
    } else if (token == "rgbd") {
      outputs.rgbd = true;
    } else if (token == "points") {
      outputs.points = true;
    } else if (token == "disparity") {
      outputs.disparity = true;
    } else {
      STEREODET_THROW_ARG() << "unknown output '" << token
                            << "' (expected rgbh, rgbd, points, disparity)";
    }
  }
  STEREODET_CHECK(outputs.Any()) << "no output named (expected rgbh, rgbd, points, disparity)";
  return outputs;
}

void EncodeDatasetOptions::Check() const {
  stereo.Check();
  STEREODET_CHECK(outputs.Any()) << "EncodeDatasetOptions: no output chosen";
  STEREODET_CHECK_GE(num_threads, 0);
}

std::string DatasetManifest(const EncodeDatasetOptions& options) {
  const StereoOptions& o = options.stereo;
  nlohmann::json j;
  j["encode"] = DatasetOutputsName(options.outputs);
  j["disparity"] = {{"method", DisparityMethodName(o.disparity.method)},
                    {"num_disparities", o.disparity.num_disparities},
                    {"min_disparity", o.disparity.min_disparity},
                    {"uniqueness_ratio", o.disparity.uniqueness_ratio},
                    {"speckle_window_px", o.disparity.speckle_window_px},
                    {"speckle_range_px", o.disparity.speckle_range_px},
                    {"left_right_max_diff_px", o.disparity.left_right_max_diff_px},
                    {"bm_block_size", o.disparity.bm.block_size},
                    {"sgbm_block_size", o.disparity.sgbm.block_size}};
  j["ground"] = {{"enabled", o.ground.enabled},
                 {"nominal_camera_height_m", o.ground.nominal_camera_height_m}};
  j["height_code"] = {
      {"min_m", o.height.min_m}, {"max_m", o.height.max_m}, {"levels", 511}, {"no_stereo", 0}};
  j["depth_code"] = {
      {"min_m", o.depth.min_m}, {"max_m", o.depth.max_m}, {"bits", o.depth.bits}, {"no_stereo", 0}};
  j["points"] = {{"max_depth_m", o.points.max_depth_m},
                 {"min_height_m", o.points.min_height_m},
                 {"max_height_m", o.points.max_height_m},
                 {"beams", o.points.beams}};
  j["blur"] = {{"sigma_px", o.blur.sigma_px}, {"mode", BlurModeName(o.blur.mode)}};
  return j.dump(2) + "\n";
}

std::string GroundFitLine(const GroundPlaneFit& fit) {
  const Eigen::Vector3d& n = fit.plane.normal_in_rect;
  return fmt::format(
      "fitted {} normal {:.6f} {:.6f} {:.6f} offset_m {:.4f} inliers {} samples {} tilt_deg {:.3f} "
      "reason {}\n",
      fit.fitted ? 1 : 0, n.x(), n.y(), n.z(), fit.plane.offset_m, fit.inliers, fit.samples,
      fit.tilt_deg, fit.reason);
}

EncodeDatasetResult EncodeDataset(const KittiDataset& dataset, const std::vector<std::string>& ids,
                                  const fs::path& out, const EncodeDatasetOptions& options) {
  options.Check();
  STEREODET_CHECK_IO(!ids.empty()) << "no frames to process in " << dataset.SubsetDir();
  const std::vector<std::string> missing =
      FindMissingFiles(dataset, ids, {.image_left = true, .image_right = true, .calib = true});
  STEREODET_CHECK_IO(missing.empty())
      << missing.size() << " input files are missing, first: " << missing.front();

  CheckOutputDoesNotOverlapInputs(
      "--out", out, {{"--data", dataset.SubsetDir()}, {"--data", dataset.root() / "ImageSets"}});
  const OutputLock lock(out);  // two runs into one folder would interleave
  const std::string data_dir = fs::weakly_canonical(fs::absolute(dataset.SubsetDir())).string();
  // Resuming with other settings would mix outputs; refuse, naming the settings, unless force
  // recomputes everything. Other outputs ("encode") are added to the folder's.
  const fs::path settings_path = out / "stereo.json";
  const std::optional<RunManifest> previous =
      fs::exists(out / kRunManifestFile) ? ReadRunManifest(out) : std::nullopt;
  EncodeDatasetOptions recorded = options;  // what stereo.json will say
  if (fs::exists(settings_path) && !options.force) {
    const std::string old_text = ReadFile(settings_path);
    const std::string differences =
        DifferingSettings(old_text, DatasetManifest(options), settings_path);
    STEREODET_CHECK_IO(differences.empty())
        << settings_path.string() << " records different settings: " << differences
        << "; use another --out, or --force to recompute every frame";
    recorded.outputs = UnionOutputs(old_text, options.outputs);
  }
  if (previous && !options.force) {
    for (const auto& [name, path] : previous->inputs) {
      STEREODET_CHECK_IO(name != "data" || path == data_dir)
          << out.string() << " holds outputs computed from --data " << path
          << " (its run.json), not " << data_dir << "; use another --out, or --force to "
          << "recompute every frame";
    }
  }
  fs::create_directories(out);
  // force: the outputs not asked for this time are another run's; they go.
  if (options.force && fs::exists(settings_path)) {
    const DatasetOutputs& o = options.outputs;
    const bool blurred_rgbd = o.rgbd && options.stereo.blur.sigma_px > 0;
    for (const auto& [folder, kept] :
         std::vector<std::pair<const char*, bool>>{{"rgbh", o.rgbh},
                                                   {"depth", o.rgbd},
                                                   {"height", o.rgbd},
                                                   {"image_2", blurred_rgbd},
                                                   {"velodyne", o.points},
                                                   {"disparity", o.disparity}}) {
      if (!kept) fs::remove_all(out / folder);
    }
  }
  // Which settings produced a frame: ground/ID.txt (written last) records this hash, so a resumed
  // run redoes every frame made with other settings or from other data, whatever stereo.json says.
  const std::string settings = DatasetManifest(recorded);
  EncodeDatasetOptions without_outputs = options;
  without_outputs.outputs = DatasetOutputs{};
  const std::string frame_hash = HashHex(Fnv1a64(
      data_dir, Fnv1a64(std::string_view("\0", 1), Fnv1a64(DatasetManifest(without_outputs)))));
  WriteFileAtomically(settings_path, settings);

  RunManifest manifest;
  manifest.tool = "stereo";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"data", data_dir}};
  manifest.settings_json = settings;
  std::map<std::string, std::string> frames;  // id -> settings hash, the folder's whole list
  if (previous && !options.force) {
    for (const auto& [id, hash] : previous->frames) frames[id] = hash;
  }
  auto write_manifest = [&] {
    manifest.frames.assign(frames.begin(), frames.end());
    WriteRunManifest(out, manifest);
  };
  write_manifest();

  const DatasetOutputs& outputs = options.outputs;
  const bool blurred = options.stereo.blur.sigma_px > 0;
  StageTimes times;
  std::atomic<int> done{0}, skipped{0}, kept{0}, fitted{0};
  std::mutex mutex;  // guards the fallback reasons and the disparity error sums
  std::map<std::string, int> fallback_reasons;
  DisparityErrorStats total_error;
  double bad_sum = 0, d1_sum = 0;  // pixel counts, for the pooled rates
  ProgressReporter progress("stereo", static_cast<int64_t>(ids.size()), options.progress);

  ParallelFor(
      ids.size(),
      [&](size_t i) {
        const std::string& id = ids[i];
        const FrameOutputs paths = OutputPaths(out, id);
        const FramePaths in = dataset.Paths(id);
        // A frame is valid when its ground file records this run's settings hash; then only its
        // missing files are written (an added output), and with all there it is done.
        const bool valid = !options.force && RecordedFrameHash(paths.ground) == frame_hash;
        auto needed = [&](const fs::path& path) { return !valid || !fs::exists(path); };
        bool complete = valid;
        for (const fs::path& path : RequiredPaths(paths, outputs, blurred)) {
          complete = complete && fs::exists(path);
        }
        if (complete && !options.evaluate) {
          ++skipped;
          progress.Add();
          return;
        }
        Timer timer;
        const cv::Mat left = ReadColourImage(in.image_left);
        const cv::Mat right = ReadColourImage(in.image_right);
        CheckStereoPairSize(left, right, in.image_left, in.image_right);
        CheckImageFitsMatcher(options.stereo.disparity, left.size(), in.image_left);
        const StereoGeometry geometry = StereoGeometry::FromCalibration(ReadCalibration(in.calib));
        times.Add("decode", timer.ElapsedSeconds());

        // Only what is missing: a complete frame (evaluate) needs the disparity alone.
        const bool write_rgbh = outputs.rgbh && needed(paths.rgbh);
        const bool write_rgbd = outputs.rgbd && (needed(paths.depth) || needed(paths.height) ||
                                                 (blurred && needed(paths.image)));
        const bool write_points = outputs.points && needed(paths.points);
        const bool write_disparity = outputs.disparity && needed(paths.disparity);
        // One per frame: OpenCV's matchers are not thread-safe.
        StereoEncoder encoder(options.stereo);
        const StereoEncoding encoding = encoder.Encode(
            left, right, geometry,
            {.rgbh = write_rgbh, .depth = write_rgbd, .points = write_points}, &times);

        timer.Restart();
        if (write_rgbh) WriteImageAtomically(paths.rgbh, encoding.rgbh);
        if (write_rgbd) {
          WriteImageAtomically(paths.depth, encoding.depth_code);
          WriteImageAtomically(paths.height, encoding.height_code);
          if (blurred) WriteImageAtomically(paths.image, encoding.network_image);
        }
        if (write_points) {
          fs::create_directories(paths.points.parent_path());
          WriteVelodyne(paths.points, encoding.points);
        }
        if (write_disparity) {
          fs::create_directories(paths.disparity.parent_path());
          WriteKittiDisparity(paths.disparity, encoding.disparity_px);
        }
        // Written last: its presence (with the others) and its settings hash mark the frame done.
        if (!complete) {
          WriteFileAtomically(paths.ground, kGroundFileHeader + GroundFitLine(encoding.ground) +
                                                "settings " + frame_hash + "\n");
        } else {
          ++kept;
        }
        times.Add("write", timer.ElapsedSeconds());

        if (encoding.ground.fitted) {
          ++fitted;
        } else {
          std::lock_guard lock(mutex);
          ++fallback_reasons[encoding.ground.reason.substr(0, encoding.ground.reason.find(" ("))];
        }
        if (options.evaluate) {
          STEREODET_CHECK_IO(fs::exists(in.disparity))
              << "--evaluate: no ground-truth disparity " << in.disparity;
          const DisparityErrorStats stats =
              EvaluateDisparity(encoding.disparity_px, ReadKittiDisparity(in.disparity));
          std::lock_guard lock(mutex);
          total_error.ground_truth_pixels += stats.ground_truth_pixels;
          total_error.estimated_pixels += stats.estimated_pixels;
          bad_sum += stats.bad_rate * stats.estimated_pixels;
          d1_sum += stats.d1_rate * stats.estimated_pixels;
          total_error.mean_abs_error_px += stats.mean_abs_error_px * stats.estimated_pixels;
        }
        ++done;
        progress.Add();
      },
      options.num_threads);
  progress.Finish();
  for (const std::string& id : ids) frames[id] = frame_hash;
  write_manifest();

  EncodeDatasetResult result;
  result.encoded = done.load();
  result.skipped = skipped.load();
  result.kept = kept.load();
  result.ground_fitted = fitted.load();
  result.ground_fallbacks = std::move(fallback_reasons);
  result.stage_times = times.Format();
  if (total_error.estimated_pixels > 0) {
    const double n = static_cast<double>(total_error.estimated_pixels);
    result.disparity_error = total_error;
    result.disparity_error.density = n / total_error.ground_truth_pixels;
    result.disparity_error.bad_rate = bad_sum / n;
    result.disparity_error.d1_rate = d1_sum / n;
    result.disparity_error.mean_abs_error_px = total_error.mean_abs_error_px / n;
  }
  return result;
}

}  // namespace stereodet
