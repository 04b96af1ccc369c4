// `stereodet synth`: writes a synthetic KITTI-format data set (stereo pairs, LiDAR scans, labels,
// calibration, ground-truth disparity and splits): one library call, GenerateDataset, whose
// options the flags bind to.
#include <fmt/format.h>

#include <cstdio>
#include <string>

#include "stereodet/cli/commands.h"
#include "stereodet/synth/generator.h"

namespace stereodet::cli {

void AddSynthCommand(CLI::App& app) {
  auto options = std::make_shared<DatasetOptions>();
  auto quiet = std::make_shared<bool>(false);
  auto verbose = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("synth", CommandDescription("synth"));
  cmd->add_option("--out", options->out, "output folder (the data set root)")->required();
  cmd->add_option("--frames", options->frames, "number of frames")->capture_default_str();
  AddSeedOption(cmd, &options->seed, "random seed");
  cmd->add_option("--width", options->synth.width, "image width, px")->capture_default_str();
  cmd->add_option("--height", options->synth.height, "image height, px")->capture_default_str();
  cmd->add_option("--val-fraction", options->val_fraction, "share of frames in the val split")
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "worker threads, 0 = all cores")
      ->capture_default_str();
  cmd->add_option("--density", options->synth.scene.object_density,
                  "object density multiplier (1 = KITTI-like)")
      ->capture_default_str();
  cmd->add_option("--png-compression", options->png_compression, "PNG zlib level 0..9")
      ->capture_default_str();
  cmd->add_flag(
      "--no-lidar", [options](int64_t) { options->synth.lidar = false; },
      "write empty velodyne scans (faster)");
  cmd->add_flag(
      "--flat-roads", [options](int64_t) { options->synth.scene.road_shapes = false; },
      "straight, flat roads without side streets (the road model before settings version 4)");
  AddShardOption(cmd, &options->shard);
  cmd->add_flag("--quiet", *quiet, "no progress output");
  cmd->add_flag("--verbose", *verbose, "after the summary line, the time each stage took");
  cmd->callback([options, quiet, verbose] {
    if (*quiet) options->progress.stream = nullptr;
    const DatasetSummaryLine s = GenerateDataset(*options);
    if (!*quiet) {
      fmt::print(
          "synth: {} frames written, {} already there, {} labels, train {} / val {}, {:.1f} s\n",
          s.generated, s.skipped, s.objects, s.train, s.val, s.seconds);
      if (*verbose && s.generated > 0) fmt::print("{}", s.stage_times);
    }
  });
}

}  // namespace stereodet::cli
