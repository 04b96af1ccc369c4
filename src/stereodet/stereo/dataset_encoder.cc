#include "stereodet/stereo/dataset_encoder.h"

#include <fmt/format.h>

#include <atomic>
#include <mutex>
#include <nlohmann/json.hpp>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/timer.h"

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

  fs::create_directories(out);
  // Resuming with other settings would mix outputs; refuse unless force recomputes everything.
  const std::string settings = DatasetManifest(options);
  const fs::path settings_path = out / "stereo.json";
  if (fs::exists(settings_path) && !options.force) {
    STEREODET_CHECK_IO(ReadFile(settings_path) == settings)
        << settings_path << " records different settings; use another --out, or --force to "
        << "recompute every frame";
  }
  WriteFileAtomically(settings_path, settings);

  const DatasetOutputs& outputs = options.outputs;
  const bool blurred = options.stereo.blur.sigma_px > 0;
  StageTimes times;
  std::atomic<int> done{0}, skipped{0}, fitted{0};
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
        bool complete = !options.force && !options.evaluate;
        for (const fs::path& path : RequiredPaths(paths, outputs, blurred)) {
          complete = complete && fs::exists(path);
        }
        if (complete) {
          ++skipped;
          progress.Add();
          return;
        }
        Timer timer;
        const cv::Mat left = ReadColourImage(in.image_left);
        const cv::Mat right = ReadColourImage(in.image_right);
        const StereoGeometry geometry = StereoGeometry::FromCalibration(ReadCalibration(in.calib));
        times.Add("decode", timer.ElapsedSeconds());

        // One per frame: OpenCV's matchers are not thread-safe.
        StereoEncoder encoder(options.stereo);
        const StereoEncoding encoding = encoder.Encode(
            left, right, geometry,
            {.rgbh = outputs.rgbh, .depth = outputs.rgbd, .points = outputs.points}, &times);

        timer.Restart();
        if (outputs.rgbh) WriteImageAtomically(paths.rgbh, encoding.rgbh);
        if (outputs.rgbd) {
          WriteImageAtomically(paths.depth, encoding.depth_code);
          WriteImageAtomically(paths.height, encoding.height_code);
          if (blurred) WriteImageAtomically(paths.image, encoding.network_image);
        }
        if (outputs.points) {
          fs::create_directories(paths.points.parent_path());
          WriteVelodyne(paths.points, encoding.points);
        }
        if (outputs.disparity) {
          fs::create_directories(paths.disparity.parent_path());
          WriteKittiDisparity(paths.disparity, encoding.disparity_px);
        }
        // Written last: its presence (with the others) marks the frame done.
        WriteFileAtomically(paths.ground, kGroundFileHeader + GroundFitLine(encoding.ground));
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

  EncodeDatasetResult result;
  result.encoded = done.load();
  result.skipped = skipped.load();
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
