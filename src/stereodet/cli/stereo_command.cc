// `stereodet stereo`: turns a KITTI-format dataset into the stereo inputs the detectors need
// (RGB-H, RGB-D channels, stereo point clouds, disparity maps), `stereodet stereo frame` into
// pictures, and `stereodet stereo scene` writes a tiny dataset to try them on. Each is one library
// call (EncodeDataset, WriteFramePictures, WritePlanarSceneDataset); this file binds the flags to
// their options and prints.
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/cli/stereo_flags.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/stereo/frame_pictures.h"
#include "stereodet/stereo/planar_scene.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet::cli {
namespace {

// The flags of `stereo` and `stereo frame` that are not fields of StereoOptions.
struct StereoArgs {
  std::string data;
  std::string subset = "training";
  std::string out;
  StereoFlagText stereo;
  std::vector<CLI::Option*> stereo_flags;  // AddStereoFlags'
  std::string stereo_settings;             // --stereo-settings FILE
  std::string blur_mode = BlurModeName(BlurOptions().mode);
  bool quiet = false;
  bool verbose = false;  // --verbose: the stage times after the summary
};

// The flags `stereo` and `stereo frame` share, bound to `args` and to the fields of `options`.
void AddSharedOptions(CLI::App* cmd, StereoArgs& args, StereoOptions& options) {
  cmd->add_option("--data", args.data,
                  "dataset root (holds training/, testing/, ImageSets/) (required)");
  cmd->add_option("--subset", args.subset, "training or testing")
      ->check(CLI::IsMember({"training", "testing"}))
      ->capture_default_str();
  cmd->add_option("--out", args.out, "output folder (required)");
  args.stereo_flags = AddStereoFlags(cmd, options, args.stereo);
  cmd->add_option("--stereo-settings", args.stereo_settings,
                  "take the matching, ground and height settings from this file: an RGB-H/RGB-D "
                  "model's model.json or a stereo folder's stereo.json (stereo flags given as well "
                  "apply over it), so the outputs fit that model or folder");
  cmd->add_option("--blur-sigma", options.blur.sigma_px,
                  "Gaussian blur sigma in px (0 = none), to model defocus")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--blur-mode", args.blur_mode,
                  "image: blur only the network's image; both: blur both images before matching")
      ->check(CLI::IsMember({"image", "both"}))
      ->capture_default_str();
  cmd->add_option("--beams", options.points.beams,
                  "point clouds: subsample to this many LiDAR-like beams (0 = keep all points)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--max-depth", options.points.max_depth_m,
                  "point clouds: drop points beyond this depth, m")
      ->capture_default_str();
  cmd->add_flag("--quiet", args.quiet, "no progress or summary output");
  cmd->add_flag("--verbose", args.verbose, "after the summary, the time each stage took");
}

// `defaults` with the stereo settings of `path` over it: a model.json's "stereo" record (an RGB-H
// or RGB-D model) or a stereo.json's disparity, ground and height_code (StereoOptionsFromJson).
StereoOptions ReadStereoSettingsFile(const std::string& path, const StereoOptions& defaults) {
  const std::string text = ReadFile(path);  // regular files only, named in its errors
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(path, 0, "", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw ParseError(path, 0, "", "expected a JSON object");
  if (j.contains("stereo")) {
    if (!j["stereo"].is_object()) throw ParseError(path, 0, "stereo", "expected an object");
    return StereoOptionsFromJson(j["stereo"].dump(), path, defaults);
  }
  if (!j.contains("disparity")) {
    throw ParseError(path, 0, "stereo",
                     "holds no stereo settings (neither a model.json with a \"stereo\" record, "
                     "as RGB-H and RGB-D models have, nor a stereo.json)");
  }
  return StereoOptionsFromJson(text, path, defaults);
}

// The named settings into `options`, then its Check().
void FinishOptions(StereoArgs& args, StereoOptions& options) {
  const auto blur_mode = ParseBlurMode(args.blur_mode);
  STEREODET_CHECK(blur_mode.has_value())
      << "blur mode must be 'image' or 'both', got '" << args.blur_mode << "'";
  options.blur.mode = *blur_mode;
  if (args.stereo_settings.empty()) {
    FinishStereoFlags(args.stereo, options);
    return;
  }
  // The file's settings over the flags' (blur and point settings stay the flags'), then the
  // stereo flags the user gave over the file's.
  const StereoOptions base = ReadStereoSettingsFile(args.stereo_settings, options);
  ApplyGivenStereoFlags(args.stereo_flags, base, options, args.stereo);
}

struct RunArgs {
  StereoArgs shared;
  EncodeDatasetOptions options;
  std::string split;
  std::string encode = DatasetOutputsName(EncodeDatasetOptions().outputs);
};

void RunStereo(RunArgs& args) {
  STEREODET_CHECK(!args.shared.data.empty()) << "stereo: --data is required";
  STEREODET_CHECK(!args.shared.out.empty()) << "stereo: --out is required";
  EncodeDatasetOptions& options = args.options;
  FinishOptions(args.shared, options.stereo);
  try {
    options.outputs = ParseDatasetOutputs(args.encode);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--encode: ") + e.what());
  }
  if (args.shared.quiet) options.progress.stream = nullptr;
  options.command_line = ProcessCommandLine();
  const KittiDataset dataset(args.shared.data, args.shared.subset);
  const std::vector<std::string> ids =
      args.split.empty() ? dataset.ListIds() : dataset.ReadSplit(args.split);
  const EncodeDatasetResult result = EncodeDataset(dataset, ids, args.shared.out, options);

  if (args.shared.quiet) return;
  fmt::print("stereo: {} frames encoded, {} already done; outputs in {}\n",
             result.encoded - result.kept, result.skipped + result.kept, args.shared.out);
  if (result.kept > 0) {
    fmt::print("  {} of the frames already done were recomputed for --evaluate only (files kept)\n",
               result.kept);
  }
  if (result.encoded > 0) {
    fmt::print("ground plane: fitted in {} frames, nominal fallback in {}\n", result.ground_fitted,
               result.encoded - result.ground_fitted);
    for (const auto& [reason, count] : result.ground_fallbacks) {
      fmt::print("  {}: {}\n", reason, count);
    }
    if (args.shared.verbose) fmt::print("stage times:\n{}", result.stage_times);
  }
  if (!result.ground_suspect.empty()) {
    const GroundPlaneOptions& ground = options.stereo.ground;
    std::string first;
    for (size_t i = 0; i < result.ground_suspect.size() && i < 5; ++i) {
      first += (i > 0 ? ", " : "") + result.ground_suspect[i];
    }
    fmt::print(stderr,
               "stereodet: warning: the ground fit of {} frames is beyond the tolerance (tilt > {} "
               "deg or camera height off {} m by > {} m), e.g. {}; {}: see {}/{}\n",
               result.ground_suspect.size(), ground.warn_tilt_deg, ground.nominal_camera_height_m,
               ground.warn_camera_height_m, first,
               ground.suspect_uses_prior ? "the nominal plane was used there"
                                         : "--ground-prior uses the nominal plane there",
               args.shared.out, kGroundSummaryFile);
  }
  const DisparityErrorStats& error = result.disparity_error;
  if (options.evaluate && error.estimated_pixels > 0) {
    fmt::print(
        "disparity vs ground truth ({} frames): density {:.4f}, D1 {:.4f}, bad-2.0 {:.4f}, mean "
        "|error| {:.3f} px\n",
        result.encoded, error.density, error.d1_rate, error.bad_rate, error.mean_abs_error_px);
    fmt::print(
        "  D1-all (KITTI: over ground-truth pixels, a missing estimate is an error) {:.4f}; D1 of "
        "the estimated pixels {:.4f} at density {:.4f}; in {}/{}\n",
        error.d1_all_rate, error.d1_rate, error.density, args.shared.out, kDisparityEvaluationFile);
  }
  std::fflush(stdout);
}

struct FrameArgs {
  StereoArgs shared;
  StereoOptions options;
  std::string id;
};

void RunFrame(FrameArgs& args) {
  STEREODET_CHECK(!args.shared.data.empty()) << "stereo frame: --data is required";
  STEREODET_CHECK(!args.shared.out.empty()) << "stereo frame: --out is required";
  STEREODET_CHECK(!args.id.empty()) << "stereo frame: --id is required";
  FinishOptions(args.shared, args.options);
  const KittiDataset dataset(args.shared.data, args.shared.subset);
  const FramePicturesResult result =
      WriteFramePictures(dataset, args.id, args.shared.out, args.options);
  if (!args.shared.quiet) {
    fmt::print("{}: {} of {} pixels with stereo ({:.1f}%), {} points\n", args.id,
               result.stereo_pixels, result.total_pixels,
               100.0 * result.stereo_pixels / result.total_pixels, result.points);
    fmt::print("{}", GroundFitLine(result.ground));
    fmt::print("wrote {}/{}_{{disparity,depth,height,bev}}.png\n", args.shared.out, args.id);
    fmt::print("wrote {}/{}_{{disparity,depth,height,bev}}_key.png (with colour bar and caption)\n",
               args.shared.out, args.id);
  }
}

struct SceneArgs {
  std::string out;
  PlanarSceneDatasetOptions options;
};

void RunScene(const SceneArgs& args) {
  STEREODET_CHECK(!args.out.empty()) << "stereo scene: --out is required";
  STEREODET_CHECK(args.options.frames >= 1) << "stereo scene: --frames must be >= 1";
  WritePlanarSceneDataset(args.out, args.options);
  fmt::print("stereo scene: wrote {} frames of {}x{} to {}\n", args.options.frames,
             args.options.width_px, args.options.height_px, args.out);
}

}  // namespace

void AddStereoCommand(CLI::App& app) {
  auto run = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand("stereo", CommandDescription("stereo"));
  AddSharedOptions(cmd, run->shared, run->options.stereo);
  cmd->add_option("--split", run->split,
                  "split file (one frame id per line), or a name under DATA/ImageSets such as val");
  cmd->add_option("--encode", run->encode, "comma-separated outputs: rgbh, rgbd, points, disparity")
      ->capture_default_str();
  cmd->add_option("--threads", run->options.num_threads, "frames in parallel, 0 = all cores")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--force", run->options.force,
                "recompute every frame, accept other settings or --data, and remove the outputs "
                "not chosen this time");
  AddShardOption(cmd, &run->options.shard);
  cmd->add_flag("--evaluate", run->options.evaluate,
                "compare the disparity with the dataset's ground truth (disp_noc_0/, written by "
                "`stereodet synth`) and print density and KITTI D1");

  auto frame = std::make_shared<FrameArgs>();
  CLI::App* frame_cmd = cmd->add_subcommand(
      "frame",
      "Write pictures of one frame: OUT/ID_disparity.png, _depth.png, _height.png (colourized, "
      "black = no stereo) and _bev.png (the stereo point cloud from above, 80 x 80 m).");
  AddSharedOptions(frame_cmd, frame->shared, frame->options);
  frame_cmd->add_option("--id", frame->id, "frame id, e.g. 000123 (required)");
  frame_cmd->callback([frame]() { RunFrame(*frame); });

  auto scene = std::make_shared<SceneArgs>();
  CLI::App* scene_cmd = cmd->add_subcommand(
      "scene",
      "Write a tiny KITTI-layout dataset of textured road-and-wall scenes with exact disparity "
      "(training/{image_2,image_3,calib,disp_noc_0}, ImageSets/all.txt), for trying the stereo "
      "command and for tests.");
  scene_cmd->add_option("--out", scene->out, "dataset root to write (required)");
  scene_cmd->add_option("--frames", scene->options.frames, "number of frames")
      ->capture_default_str();
  scene_cmd->add_option("--width", scene->options.width_px, "image width, px")
      ->check(CLI::Range(64, 1242))
      ->capture_default_str();
  scene_cmd->add_option("--height", scene->options.height_px, "image height, px")
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
