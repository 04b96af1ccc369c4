#include "stereodet/stereo/dataset_encoder.h"

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/rgbh.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
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

// The settings stereo.json recorded before every matcher and ground setting was (session 5). Those
// added since are left out of the frame hash while they hold their default, and read as their
// default when an older stereo.json lacks them: folders written before keep resuming.
bool IsOriginalSetting(const std::string& key) {
  static const std::set<std::string> kOriginal = {"encode",
                                                  "disparity.method",
                                                  "disparity.num_disparities",
                                                  "disparity.min_disparity",
                                                  "disparity.uniqueness_ratio",
                                                  "disparity.speckle_window_px",
                                                  "disparity.speckle_range_px",
                                                  "disparity.left_right_max_diff_px",
                                                  "disparity.bm_block_size",
                                                  "disparity.sgbm_block_size",
                                                  "ground.enabled",
                                                  "ground.nominal_camera_height_m",
                                                  "height_code.min_m",
                                                  "height_code.max_m",
                                                  "height_code.levels",
                                                  "height_code.no_stereo",
                                                  "depth_code.min_m",
                                                  "depth_code.max_m",
                                                  "depth_code.bits",
                                                  "depth_code.no_stereo",
                                                  "points.max_depth_m",
                                                  "points.min_height_m",
                                                  "points.max_height_m",
                                                  "points.beams",
                                                  "blur.sigma_px",
                                                  "blur.mode"};
  return kOriginal.count(key) > 0;
}

// The JSON text of a setting's default ("a.b" keys of the default options' manifest).
std::string DefaultSetting(const std::string& key) {
  static const std::map<std::string, std::string> kDefaults = [] {
    std::map<std::string, std::string> flat;
    Flatten(nlohmann::json::parse(DatasetManifest(EncodeDatasetOptions{})), "", flat);
    return flat;
  }();
  const auto it = kDefaults.find(key);
  return it == kDefaults.end() ? std::string() : it->second;
}

// `manifest` without the settings added since session 5 that hold their default.
std::string WithoutAddedDefaults(const std::string& manifest) {
  nlohmann::json j = nlohmann::json::parse(manifest);
  for (auto& [section, values] : j.items()) {
    if (!values.is_object()) continue;
    std::vector<std::string> drop;
    for (const auto& [name, value] : values.items()) {
      const std::string key = section + "." + name;
      if (!IsOriginalSetting(key) && value.dump() == DefaultSetting(key)) drop.push_back(name);
    }
    for (const std::string& name : drop) values.erase(name);
  }
  return j.dump(2) + "\n";
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
      // A setting recorded only since session 5 reads as its default in an older manifest.
      if (!IsOriginalSetting(key) && value == DefaultSetting(key)) continue;
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

// The plane line of ground/ID.txt (its second line; ground/ID.txt exists).
std::string ReadGroundFitLine(const fs::path& ground) {
  const std::string text = ReadFile(ground);
  const size_t begin = text.find('\n');
  if (begin == std::string::npos) return {};
  const size_t end = text.find('\n', begin + 1);
  return text.substr(begin + 1, end == std::string::npos ? std::string::npos : end - begin - 1);
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
  shard.Check();
  STEREODET_CHECK(shard.Whole() || !force)
      << "a shard cannot --force (it would remove the other shards' outputs)";
}

std::string DatasetManifest(const EncodeDatasetOptions& options) {
  const StereoOptions& o = options.stereo;
  nlohmann::json j = nlohmann::json::parse(StereoSettingsJson(o));
  j["encode"] = DatasetOutputsName(options.outputs);
  j["depth_code"] = {
      {"min_m", o.depth.min_m}, {"max_m", o.depth.max_m}, {"bits", o.depth.bits}, {"no_stereo", 0}};
  j["points"] = {{"max_depth_m", o.points.max_depth_m},
                 {"min_height_m", o.points.min_height_m},
                 {"max_height_m", o.points.max_height_m},
                 {"beams", o.points.beams}};
  j["blur"] = {{"sigma_px", o.blur.sigma_px}, {"mode", BlurModeName(o.blur.mode)}};
  return j.dump(2) + "\n";
}

StereoFolderRecord ReadStereoFolder(const fs::path& dir) {
  StereoFolderRecord folder;
  folder.dir = dir;
  const fs::path settings_path = dir / "stereo.json";
  STEREODET_CHECK_IO(fs::is_regular_file(settings_path))
      << "--stereo " << dir.string() << " is not a `stereodet stereo` folder: it holds no "
      << "stereo.json";
  const std::string text = ReadFile(settings_path);
  folder.stereo = StereoOptionsFromJson(text, settings_path.string());
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(settings_path.string(), 0, "", std::string("not valid JSON: ") + e.what());
  }
  if (!j.contains("encode") || !j["encode"].is_string()) {
    throw ParseError(settings_path.string(), 0, "encode", "expected a string");
  }
  folder.outputs = ParseDatasetOutputs(j["encode"].get<std::string>());
  STEREODET_CHECK_IO(folder.outputs.rgbh || folder.outputs.rgbd)
      << settings_path.string() << " records no height images (encode \""
      << DatasetOutputsName(folder.outputs) << "\"); make them with `stereodet stereo --encode "
      << "rgbh`";
  if (j.contains("blur") && j["blur"].is_object()) {
    const double sigma = j["blur"].value("sigma_px", 0.0);
    const std::string mode = j["blur"].value("mode", std::string("image"));
    STEREODET_CHECK_IO(sigma <= 0 || ParseBlurMode(mode) != BlurMode::kBothBeforeMatching)
        << settings_path.string() << " records heights matched on blurred pairs (blur.mode \""
        << mode << "\", blur.sigma_px " << sigma << "); a detector's heights come from the "
        << "sharp pair";
  }
  if (fs::exists(dir / kRunManifestFile)) {
    if (const std::optional<RunManifest> run = ReadRunManifest(dir)) {
      for (const auto& [name, path] : run->inputs) {
        if (name == "data") folder.data_dir = path;
      }
    }
  }
  return folder;
}

void CheckStereoFolderData(const StereoFolderRecord& folder, const KittiDataset& dataset) {
  if (folder.data_dir.empty()) return;
  const std::string data_dir = fs::weakly_canonical(fs::absolute(dataset.SubsetDir())).string();
  STEREODET_CHECK_IO(folder.data_dir == data_dir)
      << "--stereo " << folder.dir.string() << " holds heights computed from --data "
      << folder.data_dir << " (its run.json), not " << data_dir;
}

cv::Mat ReadStereoFolderHeight(const StereoFolderRecord& folder, const std::string& id) {
  const FrameOutputs paths = OutputPaths(folder.dir, id);
  STEREODET_CHECK_IO(fs::exists(paths.ground))
      << "--stereo " << folder.dir.string() << " has no finished frame " << id << " (no "
      << paths.ground.string() << "); run `stereodet stereo` on this split first";
  if (folder.outputs.rgbd && fs::exists(paths.height)) {
    cv::Mat code = ReadImage(paths.height, cv::IMREAD_UNCHANGED, "height image");
    STEREODET_CHECK_IO(code.type() == CV_16UC1)
        << paths.height.string() << ": expected a 16-bit one-channel height image";
    return code;
  }
  STEREODET_CHECK_IO(fs::exists(paths.rgbh))
      << "--stereo " << folder.dir.string() << " has no height image of frame " << id << " ("
      << paths.rgbh.string() << " is missing)";
  return UnpackRgbh(ReadImage(paths.rgbh, cv::IMREAD_COLOR, "RGB-H image")).height_code;
}

cv::Mat HeightCodesAtMatchSize(const cv::Mat& full_codes, cv::Size match_size) {
  STEREODET_CHECK(match_size.width <= full_codes.cols && match_size.height <= full_codes.rows)
      << "the match size " << match_size.width << "x" << match_size.height
      << " is larger than the codes' " << full_codes.cols << "x" << full_codes.rows;
  if (match_size == full_codes.size()) return full_codes;
  cv::Mat codes;
  cv::resize(full_codes, codes, match_size, 0, 0, cv::INTER_NEAREST_EXACT);
  return codes;
}

cv::Mat ReadStereoFolderHeightAtMatchScale(const StereoFolderRecord& folder,
                                           const std::string& id) {
  const cv::Mat full = ReadStereoFolderHeight(folder, id);
  return HeightCodesAtMatchSize(full, folder.stereo.disparity.MatchSize(full.size()));
}

std::string DisparityEvaluationJson(
    const DisparityErrorStats& pooled,
    const std::vector<std::pair<std::string, DisparityErrorStats>>& frames,
    const DisparityErrorOptions& options) {
  auto stats_json = [](const DisparityErrorStats& s) {
    return nlohmann::ordered_json{{"d1_all", s.d1_all_rate},
                                  {"d1_estimated", s.d1_rate},
                                  {"density", s.density},
                                  {"bad", s.bad_rate},
                                  {"mean_abs_error_px", s.mean_abs_error_px},
                                  {"ground_truth_pixels", s.ground_truth_pixels},
                                  {"estimated_pixels", s.estimated_pixels},
                                  {"d1_outlier_pixels", s.d1_outlier_pixels},
                                  {"bad_pixels", s.bad_pixels}};
  };
  nlohmann::ordered_json j;
  j["definition"] = {
      {"d1_outlier", fmt::format("|error| > {} px and > {} x ground truth", options.d1_abs_px,
                                 options.d1_relative)},
      {"d1_all",
       "(D1 outliers + pixels with ground truth but no estimate) / pixels with ground truth; "
       "no interpolation of the holes (KITTI's devkit interpolates them first), so an upper "
       "bound of the devkit's D1-all"},
      {"d1_estimated", "D1 outliers / pixels with ground truth and an estimate"},
      {"density", "pixels with ground truth and an estimate / pixels with ground truth"},
      {"bad", fmt::format("|error| > {} px, over the estimated pixels", options.bad_threshold_px)}};
  j["frames"] = frames.size();
  j["all"] = stats_json(pooled);
  nlohmann::ordered_json per_frame = nlohmann::ordered_json::object();
  for (const auto& [id, stats] : frames) per_frame[id] = stats_json(stats);
  j["per_frame"] = per_frame;
  return j.dump(2) + "\n";
}

namespace {

// The per-frame figures of a disparity_evaluation.json (empty when there is none), exactly as
// written: counts as integers, rates as the shortest doubles that read back to the same bits.
std::map<std::string, DisparityErrorStats> ReadPerFrameDisparityErrors(const fs::path& path) {
  std::map<std::string, DisparityErrorStats> frames;
  if (!fs::exists(path)) return frames;
  try {
    const nlohmann::json j = nlohmann::json::parse(ReadFile(path));
    for (const auto& [id, f] : j.at("per_frame").items()) {
      DisparityErrorStats s;
      s.d1_all_rate = f.at("d1_all").get<double>();
      s.d1_rate = f.at("d1_estimated").get<double>();
      s.density = f.at("density").get<double>();
      s.bad_rate = f.at("bad").get<double>();
      s.mean_abs_error_px = f.at("mean_abs_error_px").get<double>();
      s.ground_truth_pixels = f.at("ground_truth_pixels").get<long>();
      s.estimated_pixels = f.at("estimated_pixels").get<long>();
      s.d1_outlier_pixels = f.at("d1_outlier_pixels").get<long>();
      s.bad_pixels = f.at("bad_pixels").get<long>();
      frames[id] = s;
    }
  } catch (const nlohmann::json::exception& e) {
    STEREODET_THROW_IO() << path.string() << ": not a disparity evaluation of this tool ("
                         << e.what() << "); remove it and rerun the shards";
  }
  return frames;
}

}  // namespace

GroundPlaneFit ParseGroundFitLine(const std::string& line, const std::string& source,
                                  const GroundPlaneOptions& options) {
  std::istringstream in(line);
  std::string fitted_key, normal_key, offset_key, inliers_key, samples_key, tilt_key, reason_key;
  int fitted = 0;
  GroundPlaneFit fit;
  Eigen::Vector3d& n = fit.plane.normal_in_rect;
  in >> fitted_key >> fitted >> normal_key >> n.x() >> n.y() >> n.z() >> offset_key >>
      fit.plane.offset_m >> inliers_key >> fit.inliers >> samples_key >> fit.samples >> tilt_key >>
      fit.tilt_deg >> reason_key;
  if (!in || fitted_key != "fitted" || normal_key != "normal" || offset_key != "offset_m" ||
      inliers_key != "inliers" || samples_key != "samples" || tilt_key != "tilt_deg" ||
      reason_key != "reason") {
    throw ParseError(source, 2, "", "not a ground plane line: '" + line + "'");
  }
  std::getline(in, fit.reason);
  fit.reason = std::string(Trim(fit.reason));
  fit.fitted = fitted == 1;
  fit.camera_height_m = fit.plane.offset_m;
  fit.suspect = fit.reason.rfind("suspect", 0) == 0 ||
                (fit.fitted && (fit.tilt_deg > options.warn_tilt_deg ||
                                std::abs(fit.plane.offset_m - options.nominal_camera_height_m) >
                                    options.warn_camera_height_m));
  return fit;
}

std::string GroundSummaryJson(const std::vector<std::pair<std::string, GroundPlaneFit>>& frames,
                              const GroundPlaneOptions& options) {
  int fitted = 0;
  double tilt_sum = 0, tilt_max = 0, height_sum = 0;
  double height_min = std::numeric_limits<double>::infinity(), height_max = -height_min;
  nlohmann::ordered_json suspect = nlohmann::ordered_json::array();
  nlohmann::ordered_json per_frame = nlohmann::ordered_json::object();
  // At ground/ID.txt's precision, so that a resumed run, which reads the frames already done from
  // there, writes the same summary.
  auto round_to = [](double value, double step) { return std::round(value / step) * step; };
  for (const auto& [id, exact] : frames) {
    GroundPlaneFit fit = exact;
    fit.tilt_deg = round_to(fit.tilt_deg, 1e-3);
    fit.camera_height_m = round_to(fit.camera_height_m, 1e-4);
    if (fit.suspect) suspect.push_back(id);
    if (fit.fitted) {
      ++fitted;
      tilt_sum += fit.tilt_deg;
      tilt_max = std::max(tilt_max, fit.tilt_deg);
      height_sum += fit.camera_height_m;
      height_min = std::min(height_min, fit.camera_height_m);
      height_max = std::max(height_max, fit.camera_height_m);
    }
    per_frame[id] = {{"fitted", fit.fitted},
                     {"suspect", fit.suspect},
                     {"tilt_deg", fit.tilt_deg},
                     {"camera_height_m", fit.camera_height_m},
                     {"inliers", fit.inliers},
                     {"samples", fit.samples},
                     {"inlier_fraction", round_to(fit.InlierFraction(), 1e-6)},
                     {"reason", fit.reason}};
  }
  nlohmann::ordered_json j;
  j["tolerance"] = {{"warn_tilt_deg", options.warn_tilt_deg},
                    {"warn_camera_height_m", options.warn_camera_height_m},
                    {"nominal_camera_height_m", options.nominal_camera_height_m},
                    {"suspect_uses_prior", options.suspect_uses_prior}};
  nlohmann::ordered_json summary;
  summary["frames"] = frames.size();
  summary["fitted"] = fitted;
  summary["fallback"] = static_cast<int>(frames.size()) - fitted;
  summary["suspect"] = suspect.size();
  if (fitted > 0) {
    summary["tilt_deg"] = {{"mean", tilt_sum / fitted}, {"max", tilt_max}};
    summary["camera_height_m"] = {
        {"mean", height_sum / fitted}, {"min", height_min}, {"max", height_max}};
  }
  summary["suspect_frames"] = suspect;
  j["summary"] = summary;
  j["per_frame"] = per_frame;
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

EncodeDatasetResult EncodeDataset(const KittiDataset& dataset,
                                  const std::vector<std::string>& all_ids, const fs::path& out,
                                  const EncodeDatasetOptions& options) {
  options.Check();
  const Shard& shard = options.shard;
  const std::vector<std::string> ids(all_ids.begin() + shard.Begin(all_ids.size()),
                                     all_ids.begin() + shard.End(all_ids.size()));
  STEREODET_CHECK_IO(!ids.empty()) << "no frames to process in " << dataset.SubsetDir();
  CheckRequiredFiles(dataset, ids, {.image_left = true, .image_right = true, .calib = true});

  CheckOutputDoesNotOverlapInputs(
      "--out", out, {{"--data", dataset.SubsetDir()}, {"--data", dataset.root() / "ImageSets"}});
  // stereo writes KITTI-named folders (velodyne/, image_2/): only into a folder of its own.
  CheckOutputFolderOwner(out, "stereo", {kMakerStereo});
  // Two runs into one folder would interleave; the shards of one run write disjoint frames.
  const OutputLock lock(out, shard.Whole()
                                 ? std::string("lock")
                                 : fmt::format("shard-{}-of-{}.lock", shard.index, shard.count));
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
  RemoveStaleTemporaries(out);
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
  const std::string frame_hash = HashHex(
      Fnv1a64(data_dir, Fnv1a64(std::string_view("\0", 1),
                                Fnv1a64(WithoutAddedDefaults(DatasetManifest(without_outputs))))));
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
    if (!shard.Whole()) {
      // The other shards' frames, as they are now: read, merged and written under one lock.
      const OutputLock manifest_lock(out, "manifest.lock", /*wait=*/true);
      if (const std::optional<RunManifest> now = ReadRunManifest(out)) {
        for (const auto& [id, hash] : now->frames) frames.emplace(id, hash);
      }
      manifest.frames.assign(frames.begin(), frames.end());
      WriteRunManifest(out, manifest);
      return;
    }
    manifest.frames.assign(frames.begin(), frames.end());
    WriteRunManifest(out, manifest);
  };
  write_manifest();

  const DatasetOutputs& outputs = options.outputs;
  const bool blurred = options.stereo.blur.sigma_px > 0;
  StageTimes times;
  std::atomic<int> done{0}, skipped{0}, kept{0}, fitted{0};
  std::mutex mutex;  // guards the fallback reasons
  std::map<std::string, int> fallback_reasons;
  std::vector<std::optional<DisparityErrorStats>> frame_errors(ids.size());  // with evaluate
  std::vector<GroundPlaneFit> ground_fits(ids.size());  // every frame's, for ground_summary.json
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
          ground_fits[i] = ParseGroundFitLine(ReadGroundFitLine(paths.ground),
                                              paths.ground.string(), options.stereo.ground);
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

        ground_fits[i] = encoding.ground;
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
          frame_errors[i] = stats;
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
  std::vector<std::pair<std::string, GroundPlaneFit>> fits;
  for (size_t i = 0; i < ids.size(); ++i) {
    fits.emplace_back(ids[i], ground_fits[i]);
    if (ground_fits[i].suspect) result.ground_suspect.push_back(ids[i]);
  }
  if (shard.Whole()) {
    WriteFileAtomically(out / kGroundSummaryFile, GroundSummaryJson(fits, options.stereo.ground));
  } else {
    // The summary is the folder's, as one run writes it: every frame of the whole list whose
    // ground file records this run's settings, read under the manifest's lock. The last shard to
    // finish therefore writes the summary of all frames.
    const OutputLock manifest_lock(out, "manifest.lock", /*wait=*/true);
    std::vector<std::pair<std::string, GroundPlaneFit>> all_fits;
    for (const std::string& id : all_ids) {
      const fs::path ground = OutputPaths(out, id).ground;
      if (RecordedFrameHash(ground) != frame_hash) continue;
      all_fits.emplace_back(id, ParseGroundFitLine(ReadGroundFitLine(ground), ground.string(),
                                                   options.stereo.ground));
    }
    WriteFileAtomically(out / kGroundSummaryFile,
                        GroundSummaryJson(all_fits, options.stereo.ground));
  }
  if (options.evaluate) {
    std::vector<DisparityErrorStats> evaluated;
    std::vector<std::pair<std::string, DisparityErrorStats>> per_frame;
    for (size_t i = 0; i < ids.size(); ++i) {
      if (!frame_errors[i]) continue;
      evaluated.push_back(*frame_errors[i]);
      per_frame.emplace_back(ids[i], *frame_errors[i]);
    }
    const DisparityErrorStats pooled = PoolDisparityErrors(evaluated);
    // Kept all zero when no pixel was estimated, as before D1-all existed.
    if (pooled.estimated_pixels > 0) result.disparity_error = pooled;
    if (shard.Whole()) {
      WriteFileAtomically(out / kDisparityEvaluationFile,
                          DisparityEvaluationJson(pooled, per_frame, DisparityErrorOptions{}));
    } else {
      // The folder's file, as one run writes it: the other shards' frames as the file holds them
      // (its numbers read back exactly), this shard's as evaluated, pooled in the order of the
      // whole list, under the manifest's lock; the last shard to finish writes that of one run.
      const OutputLock manifest_lock(out, "manifest.lock", /*wait=*/true);
      std::map<std::string, DisparityErrorStats> by_id =
          ReadPerFrameDisparityErrors(out / kDisparityEvaluationFile);
      for (const auto& [id, stats] : per_frame) by_id[id] = stats;
      std::vector<DisparityErrorStats> all_evaluated;
      std::vector<std::pair<std::string, DisparityErrorStats>> all_per_frame;
      for (const std::string& id : all_ids) {
        auto it = by_id.find(id);
        if (it == by_id.end()) continue;
        all_evaluated.push_back(it->second);
        all_per_frame.emplace_back(id, it->second);
      }
      WriteFileAtomically(out / kDisparityEvaluationFile,
                          DisparityEvaluationJson(PoolDisparityErrors(all_evaluated), all_per_frame,
                                                  DisparityErrorOptions{}));
    }
  }
  return result;
}

}  // namespace stereodet
