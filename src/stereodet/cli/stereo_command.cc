// `stereodet stereo`: turns a KITTI-format dataset into the stereo inputs the detectors need
// (RGB-H, RGB-D channels, stereo point clouds, disparity maps), and `stereodet stereo frame` into
// pictures.
#include <fmt/format.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/stereo/planar_scene.h"
#include "stereodet/stereo/stereo_encoder.h"
#include "stereodet/stereo/visualize.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/timer.h"

namespace stereodet::cli {
namespace {

namespace fs = std::filesystem;

// Options shared by `stereo` and `stereo frame`.
struct StereoArgs {
  std::string data;
  std::string subset = "training";
  std::string out;
  std::string method = "bm";
  int num_disparities = -1;  // -1: the library default
  int block_size = -1;
  double blur_sigma = 0.0;
  std::string blur_mode = "image";
  int beams = 0;
  double max_depth_m = -1;
  bool no_ground_fit = false;
  int threads = 0;
  bool quiet = false;

  StereoOptions ToOptions() const {
    StereoOptions options;
    const auto parsed_method = ParseDisparityMethod(method);
    STEREODET_CHECK(parsed_method.has_value())
        << "disparity method must be 'bm' or 'sgbm', got '" << method << "'";
    options.disparity.method = *parsed_method;
    if (num_disparities >= 0) options.disparity.num_disparities = num_disparities;
    if (block_size >= 0) {
      options.disparity.bm.block_size = block_size;
      options.disparity.sgbm.block_size = block_size;
    }
    options.blur.sigma_px = blur_sigma;
    const auto parsed_blur_mode = ParseBlurMode(blur_mode);
    STEREODET_CHECK(parsed_blur_mode.has_value())
        << "blur mode must be 'image' or 'both', got '" << blur_mode << "'";
    options.blur.mode = *parsed_blur_mode;
    options.points.beams = beams;
    if (max_depth_m > 0) options.points.max_depth_m = max_depth_m;
    options.ground.enabled = !no_ground_fit;
    options.Check();
    return options;
  }
};

void AddSharedOptions(CLI::App* cmd, StereoArgs& args) {
  cmd->add_option("--data", args.data, "dataset root (holds training/, testing/, ImageSets/)");
  cmd->add_option("--subset", args.subset, "training or testing")
      ->check(CLI::IsMember({"training", "testing"}))
      ->capture_default_str();
  cmd->add_option("--out", args.out, "output folder");
  cmd->add_option("--method", args.method, "disparity: bm (OpenCV StereoBM) or sgbm (StereoSGBM)")
      ->check(CLI::IsMember({"bm", "sgbm"}))
      ->capture_default_str();
  cmd->add_option("--num-disparities", args.num_disparities,
                  "disparity search range, px, a multiple of 16 (default 128)");
  cmd->add_option("--block-size", args.block_size,
                  "matching window side, px, odd (default BM 11, SGBM 5)");
  cmd->add_option("--blur-sigma", args.blur_sigma,
                  "Gaussian blur sigma in px (0 = none), to model defocus")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--blur-mode", args.blur_mode,
                  "image: blur only the network's image; both: blur both images before matching")
      ->check(CLI::IsMember({"image", "both"}))
      ->capture_default_str();
  cmd->add_option("--beams", args.beams,
                  "point clouds: subsample to this many LiDAR-like beams (0 = keep all points)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--max-depth", args.max_depth_m,
                  "point clouds: drop points beyond this depth, m "
                  "(default 80)");
  cmd->add_flag("--no-ground-fit", args.no_ground_fit,
                "use the nominal ground plane (camera 1.65 m up) instead of fitting it");
  cmd->add_flag("--quiet", args.quiet, "no progress or summary output");
}

enum class Output { kRgbh, kRgbd, kPoints, kDisparity };

std::set<Output> ParseEncode(const std::string& text) {
  std::set<Output> outputs;
  for (std::string_view token : Split(text, ',')) {
    token = Trim(token);
    if (token == "rgbh") {
      outputs.insert(Output::kRgbh);
    } else if (token == "rgbd") {
      outputs.insert(Output::kRgbd);
    } else if (token == "points") {
      outputs.insert(Output::kPoints);
    } else if (token == "disparity") {
      outputs.insert(Output::kDisparity);
    } else {
      STEREODET_THROW_ARG() << "--encode: unknown output '" << token
                            << "' (expected rgbh, rgbd, points, disparity)";
    }
  }
  STEREODET_CHECK(!outputs.empty()) << "--encode names no output";
  return outputs;
}

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

std::vector<fs::path> RequiredPaths(const FrameOutputs& paths, const std::set<Output>& outputs,
                                    bool blurred) {
  std::vector<fs::path> required = {paths.ground};
  if (outputs.count(Output::kRgbh)) required.push_back(paths.rgbh);
  if (outputs.count(Output::kRgbd)) {
    required.push_back(paths.depth);
    required.push_back(paths.height);
    if (blurred) required.push_back(paths.image);
  }
  if (outputs.count(Output::kPoints)) required.push_back(paths.points);
  if (outputs.count(Output::kDisparity)) required.push_back(paths.disparity);
  return required;
}

std::string GroundLine(const GroundPlaneFit& fit) {
  const Eigen::Vector3d& n = fit.plane.normal_in_rect;
  return fmt::format(
      "# ground plane in the rect frame: n . X + offset = 0, n up; fitted 1 = RANSAC fit used, 0 = "
      "nominal fallback\nfitted {} normal {:.6f} {:.6f} {:.6f} offset_m {:.4f} inliers {} samples "
      "{} tilt_deg {:.3f} reason {}\n",
      fit.fitted ? 1 : 0, n.x(), n.y(), n.z(), fit.plane.offset_m, fit.inliers, fit.samples,
      fit.tilt_deg, fit.reason);
}

// The settings that change the bytes of the outputs; a resumed run must use the same.
nlohmann::json OptionsJson(const StereoOptions& o, const std::string& encode) {
  nlohmann::json j;
  j["encode"] = encode;
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
  return j;
}

struct RunArgs {
  StereoArgs shared;
  std::string split;
  std::string encode = "rgbh";
  bool force = false;
  bool evaluate = false;
};

void RunStereo(const RunArgs& args) {
  STEREODET_CHECK(!args.shared.data.empty()) << "stereo: --data is required";
  STEREODET_CHECK(!args.shared.out.empty()) << "stereo: --out is required";
  const StereoOptions options = args.shared.ToOptions();
  const std::set<Output> outputs = ParseEncode(args.encode);
  const KittiDataset dataset(args.shared.data, args.shared.subset);
  const std::vector<std::string> ids =
      args.split.empty() ? dataset.ListIds() : dataset.ReadSplit(args.split);
  STEREODET_CHECK_IO(!ids.empty()) << "no frames to process in " << dataset.SubsetDir();
  const std::vector<std::string> missing =
      FindMissingFiles(dataset, ids, {.image_left = true, .image_right = true, .calib = true});
  STEREODET_CHECK_IO(missing.empty())
      << missing.size() << " input files are missing, first: " << missing.front();

  const fs::path out = args.shared.out;
  fs::create_directories(out);
  // Resuming with other settings would mix outputs; refuse unless --force recomputes everything.
  const std::string settings = OptionsJson(options, args.encode).dump(2) + "\n";
  const fs::path settings_path = out / "stereo.json";
  if (fs::exists(settings_path) && !args.force) {
    STEREODET_CHECK_IO(ReadFile(settings_path) == settings)
        << settings_path << " records different settings; use another --out, or --force to "
        << "recompute every frame";
  }
  WriteFileAtomically(settings_path, settings);

  const bool blurred = options.blur.sigma_px > 0;
  StageTimes times;
  std::atomic<int> done{0}, skipped{0}, fitted{0};
  std::mutex mutex;  // guards the two maps below
  std::map<std::string, int> fallback_reasons;
  DisparityErrorStats total_error;
  double bad_sum = 0, d1_sum = 0;  // pixel counts, for the pooled rates
  ProgressOptions progress_options;
  if (args.shared.quiet) progress_options.stream = nullptr;
  ProgressReporter progress("stereo", static_cast<int64_t>(ids.size()), progress_options);

  ParallelFor(
      ids.size(),
      [&](size_t i) {
        const std::string& id = ids[i];
        const FrameOutputs paths = OutputPaths(out, id);
        const FramePaths in = dataset.Paths(id);
        bool complete = !args.force && !args.evaluate;
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

        StereoEncoder encoder(options);  // one per frame: OpenCV's matchers are not thread-safe
        const StereoEncoding encoding =
            encoder.Encode(left, right, geometry,
                           {.rgbh = outputs.count(Output::kRgbh) > 0,
                            .depth = outputs.count(Output::kRgbd) > 0,
                            .points = outputs.count(Output::kPoints) > 0},
                           &times);

        timer.Restart();
        if (outputs.count(Output::kRgbh)) WriteImageAtomically(paths.rgbh, encoding.rgbh);
        if (outputs.count(Output::kRgbd)) {
          WriteImageAtomically(paths.depth, encoding.depth_code);
          WriteImageAtomically(paths.height, encoding.height_code);
          if (blurred) WriteImageAtomically(paths.image, encoding.network_image);
        }
        if (outputs.count(Output::kPoints)) {
          fs::create_directories(paths.points.parent_path());
          WriteVelodyne(paths.points, encoding.points);
        }
        if (outputs.count(Output::kDisparity)) {
          fs::create_directories(paths.disparity.parent_path());
          WriteKittiDisparity(paths.disparity, encoding.disparity_px);
        }
        // Written last: its presence (with the others) marks the frame done.
        WriteFileAtomically(paths.ground, GroundLine(encoding.ground));
        times.Add("write", timer.ElapsedSeconds());

        if (encoding.ground.fitted) {
          ++fitted;
        } else {
          std::lock_guard lock(mutex);
          ++fallback_reasons[encoding.ground.reason.substr(0, encoding.ground.reason.find(" ("))];
        }
        if (args.evaluate) {
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
      args.shared.threads);
  progress.Finish();

  if (args.shared.quiet) return;
  fmt::print("stereo: {} frames encoded, {} already done; outputs in {}\n", done.load(),
             skipped.load(), out.string());
  if (done > 0) {
    fmt::print("ground plane: fitted in {} frames, nominal fallback in {}\n", fitted.load(),
               done.load() - fitted.load());
    for (const auto& [reason, count] : fallback_reasons) fmt::print("  {}: {}\n", reason, count);
    fmt::print("stage times:\n{}", times.Format());
  }
  if (args.evaluate && total_error.estimated_pixels > 0) {
    const double n = static_cast<double>(total_error.estimated_pixels);
    fmt::print(
        "disparity vs ground truth ({} frames): density {:.4f}, D1 {:.4f}, bad-2.0 {:.4f}, mean "
        "|error| {:.3f} px\n",
        done.load(), n / total_error.ground_truth_pixels, d1_sum / n, bad_sum / n,
        total_error.mean_abs_error_px / n);
  }
  std::fflush(stdout);
}

struct FrameArgs {
  StereoArgs shared;
  std::string id;
};

void RunFrame(const FrameArgs& args) {
  STEREODET_CHECK(!args.shared.data.empty()) << "stereo frame: --data is required";
  STEREODET_CHECK(!args.shared.out.empty()) << "stereo frame: --out is required";
  STEREODET_CHECK(!args.id.empty()) << "stereo frame: --id is required";
  StereoOptions options = args.shared.ToOptions();
  const KittiDataset dataset(args.shared.data, args.shared.subset);
  const FramePaths in = dataset.Paths(args.id);
  const cv::Mat left = ReadColourImage(in.image_left);
  const cv::Mat right = ReadColourImage(in.image_right);
  const StereoGeometry geometry = StereoGeometry::FromCalibration(ReadCalibration(in.calib));
  StereoEncoder encoder(options);
  const StereoEncoding encoding =
      encoder.Encode(left, right, geometry, {.rgbh = false, .depth = false, .points = true});
  const fs::path out = args.shared.out;
  fs::create_directories(out);
  const cv::Mat depth = DepthFromDisparity(encoding.disparity_px, geometry);
  const cv::Mat height =
      HeightFromDisparity(encoding.disparity_px, geometry, encoding.ground.plane);
  const std::vector<std::pair<std::string, cv::Mat>> pictures = {
      {"disparity", ColourizeDisparity(encoding.disparity_px, options.disparity.num_disparities)},
      {"depth", ColourizeDepth(depth)},
      {"height", ColourizeHeight(height, options.height.min_m, options.height.max_m)},
      {"bev", RenderBirdsEye(encoding.points)}};
  for (const auto& [name, picture] : pictures) {
    WriteImageAtomically(out / (args.id + "_" + name + ".png"), picture);
  }
  if (!args.shared.quiet) {
    long valid = cv::countNonZero(encoding.height_code);
    fmt::print("{}: {} of {} pixels with stereo ({:.1f}%), {} points\n", args.id, valid,
               encoding.height_code.total(), 100.0 * valid / encoding.height_code.total(),
               encoding.points.size());
    fmt::print("{}",
               GroundLine(encoding.ground).substr(GroundLine(encoding.ground).find('\n') + 1));
    fmt::print("wrote {}/{}_{{disparity,depth,height,bev}}.png\n", out.string(), args.id);
  }
}

struct SceneArgs {
  std::string out;
  int frames = 2;
  int width_px = 1242, height_px = 375;
};

// A tiny KITTI-layout dataset of road-and-wall scenes with exact disparity: for tests and demos
// that should not depend on the full generator (`stereodet synth`).
void RunScene(const SceneArgs& args) {
  STEREODET_CHECK(!args.out.empty()) << "stereo scene: --out is required";
  STEREODET_CHECK(args.frames >= 1) << "stereo scene: --frames must be >= 1";
  Calibration calib = KittiLikeCalibration();
  // Keep KITTI's principal point centred in a smaller image: shift every P_i in pixels.
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();
  shift(0, 2) = -(1242 - args.width_px) / 2.0;
  shift(1, 2) = -(375 - args.height_px) / 2.0;
  for (Matrix34d& projection : calib.projection) projection = shift * projection;
  const fs::path training = fs::path(args.out) / "training";
  std::vector<std::string> ids;
  for (int i = 0; i < args.frames; ++i) {
    const std::string id = FrameId(i);
    PlanarSceneOptions options;
    options.width_px = args.width_px;
    options.height_px = args.height_px;
    options.seed = static_cast<unsigned>(i + 1);
    options.wall_depth_m = 15.0 + 10.0 * (i % 3);
    options.ground_pitch_deg = 0.5 * (i % 3) - 0.5;
    const PlanarScene scene = RenderPlanarScene(calib, options);
    WriteImageAtomically(training / "image_2" / (id + ".png"), scene.left_bgr);
    WriteImageAtomically(training / "image_3" / (id + ".png"), scene.right_bgr);
    fs::create_directories(training / "disp_noc_0");
    WriteKittiDisparity(training / "disp_noc_0" / (id + ".png"), scene.disparity_px);
    WriteCalibration(training / "calib" / (id + ".txt"), calib);
    ids.push_back(id);
  }
  WriteSplit(fs::path(args.out) / "ImageSets" / "all.txt", ids);
  fmt::print("stereo scene: wrote {} frames of {}x{} to {}\n", args.frames, args.width_px,
             args.height_px, args.out);
}

}  // namespace

void AddStereoCommand(CLI::App& app) {
  auto run = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("stereo", CommandDescription("stereo"));
  AddSharedOptions(cmd, run->shared);
  cmd->add_option("--split", run->split,
                  "split file (one frame id per line), or a name under DATA/ImageSets such as val");
  cmd->add_option("--encode", run->encode, "comma-separated outputs: rgbh, rgbd, points, disparity")
      ->capture_default_str();
  cmd->add_option("--threads", run->shared.threads, "frames in parallel, 0 = all cores")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--force", run->force, "recompute frames that are already done");
  cmd->add_flag("--evaluate", run->evaluate,
                "compare the disparity with the dataset's ground truth (disp_noc_0/, written by "
                "`stereodet synth`) and print density and KITTI D1");

  auto frame = std::make_shared<FrameArgs>();
  CLI::App* frame_cmd = cmd->add_subcommand(
      "frame",
      "Write pictures of one frame: OUT/ID_disparity.png, _depth.png, _height.png (colourized, "
      "black = no stereo) and _bev.png (the stereo point cloud from above, 80 x 80 m).");
  AddSharedOptions(frame_cmd, frame->shared);
  frame_cmd->add_option("--id", frame->id, "frame id, e.g. 000123");
  frame_cmd->callback([frame]() { RunFrame(*frame); });

  auto scene = std::make_shared<SceneArgs>();
  CLI::App* scene_cmd = cmd->add_subcommand(
      "scene",
      "Write a tiny KITTI-layout dataset of textured road-and-wall scenes with exact disparity "
      "(training/{image_2,image_3,calib,disp_noc_0}, ImageSets/all.txt), for trying the stereo "
      "command and for tests.");
  scene_cmd->add_option("--out", scene->out, "dataset root to write");
  scene_cmd->add_option("--frames", scene->frames, "number of frames")->capture_default_str();
  scene_cmd->add_option("--width", scene->width_px, "image width, px")
      ->check(CLI::Range(64, 1242))
      ->capture_default_str();
  scene_cmd->add_option("--height", scene->height_px, "image height, px")
      ->check(CLI::Range(64, 375))
      ->capture_default_str();
  scene_cmd->callback([scene]() { RunScene(*scene); });

  cmd->require_subcommand(0, 1);
  cmd->callback([run, frame_cmd, scene_cmd]() {
    if (frame_cmd->parsed() || scene_cmd->parsed()) return;
    RunStereo(*run);
  });
}

}  // namespace stereodet::cli
