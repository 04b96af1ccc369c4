// `stereodet train ssd|det3d|rpn` and `stereodet detect ssd|det3d|rpn`: the single-shot image
// detector (issue 6), the single-stage 3D point detector (issue 14) and the late-fusion two-branch
// detector with a region proposal network (issue 15).
//   stereodet train ssd --data DIR --split train --input rgb|rgbh-fixed|rgbh-learned --out
//   MODEL_DIR
//                       [--epochs N] [--resume | --force] [--seed S] [--threads N]
//                       [--width W --height H]
//   stereodet detect ssd --model MODEL_DIR --data DIR --split val --out DIR [--blur-sigma S]
//                        [stereo flags: cli/stereo_flags.h; default: the model.json's settings]
//                        [--shard K/N: OUT is shard K's folder (models/detect_shard.h)]
//   stereodet detect merge SHARD_DIR... --out DIR   (the N shard folders into one run's folder)
// Each is one library call (TrainSsd, DetectSsd, MergeDetections); the flags bind to their
// options' fields.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "stereodet/cli/commands.h"
#include "stereodet/cli/stereo_flags.h"
#include "stereodet/models/det3d/det3d_detect.h"
#include "stereodet/models/det3d/det3d_train.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/rpn/rpn_detect.h"
#include "stereodet/models/rpn/rpn_train.h"
#include "stereodet/models/ssd/ssd_detect.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/models/ssd/ssd_train.h"
#include "stereodet/models/train_common.h"
#include "stereodet/util/check.h"

namespace stereodet::cli {
namespace {

// `train` and `detect` group one subcommand per detector; whichever area registers first makes the
// group.
CLI::App* Group(CLI::App& app, const std::string& name) {
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (sub->get_name() == name) return sub;
  }
  CLI::App* group = app.add_subcommand(name, CommandDescription(name));
  group->require_subcommand(1);
  return group;
}

// The flags of `train ssd` that are not TrainSsdOptions fields.
struct TrainArgs {
  TrainSsdOptions options;
  std::string input = InputEncodingName(SsdConfig().encoding);
  StereoFlagText stereo;  // the stereo flags, bound to options.data.stereo
  std::vector<CLI::Option*> stereo_flags;
  bool quiet = false;
};

// A `detect` command's options and the flags every one has besides them.
template <typename DetectOptions>
struct DetectCommandArgs {
  DetectOptions options;
  bool quiet = false;
  bool verbose = false;  // --verbose: the stage times too
};

// The flags of `detect ssd` that are not DetectSsdOptions fields.
struct DetectArgs : DetectCommandArgs<DetectSsdOptions> {
  StereoOptions stereo;  // the stereo flags' values; options.stereo only when one was given
  StereoFlagText stereo_text;
  std::vector<CLI::Option*> stereo_flags;
};

// The flags every `train` command shares, bound to the fields of the same names in each family's
// options, in three groups so that each command's own flags keep their place in its --help. This
// one: the data (and det3d's --points after --data, when `points_dir` is given).
template <typename TrainOptions>
void AddTrainingDataFlags(CLI::App* ts, TrainOptions& t,
                          std::filesystem::path* points_dir = nullptr) {
  ts->add_option("--data", t.data_root, "dataset root (training/, ImageSets/)")->required();
  if (points_dir != nullptr) {
    ts->add_option("--points", *points_dir,
                   "stereo input: the folder `stereodet stereo --encode points` wrote");
  }
  ts->add_option("--split", t.split, "split name in ImageSets/ or a split file")
      ->capture_default_str();
}

// The last group: how much of the data and of the epochs this run trains.
template <typename TrainOptions>
void AddTrainingStopFlags(CLI::App* ts, TrainOptions& t) {
  ts->add_option("--max-frames", t.max_frames, "use only the first N frames (0 = all)")
      ->capture_default_str();
  ts->add_option("--stop-after", t.max_epochs_this_run,
                 "stop after N epochs in this run (0 = all); continue later with --resume")
      ->capture_default_str();
}

// The middle group: the model folder, the schedule, resume/force, seed, threads, device.
template <typename TrainOptions>
void AddTrainingFlags(CLI::App* ts, TrainOptions& t) {
  ts->add_option("--out", t.out_dir, "model folder (model.json, model.pt, checkpoint, log)")
      ->required();
  ts->add_option("--epochs", t.epochs, "epochs")->check(CLI::PositiveNumber)->capture_default_str();
  ts->add_option("--batch-size", t.batch_size, "frames per step")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ts->add_option("--lr", t.learning_rate, "peak learning rate (AdamW, warm-up then cosine)")
      ->capture_default_str();
  ts->add_flag("--resume", t.resume, "continue from MODEL_DIR/checkpoint.pt if present");
  ts->add_flag("--force", t.force,
               "train a new model over one already in MODEL_DIR (its files are removed)");
  AddSeedOption(ts, &t.seed, "seed of weights, data order, augmentation");
  ts->add_option("--threads", t.threads, "threads (0 = all cores)")->capture_default_str();
  ts->add_option("--device", t.device, "cpu or cuda")
      ->check(CLI::IsMember({"cpu", "cuda"}))
      ->capture_default_str();
  // Data-parallel training (models/distributed.h, docs/scale.md); torchrun's variables fill what
  // is not given (CompleteFromEnvironment).
  ts->add_option("--world-size", t.distributed.world_size,
                 "processes training together, each on batch-size / N frames of every step "
                 "(WORLD_SIZE when not given)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ts->add_option("--rank", t.distributed.rank,
                 "this process's rank, 0 to world-size - 1; rank 0 writes the model folder (RANK "
                 "when not given)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  ts->add_option(
        "--rendezvous", t.distributed.rendezvous,
        "where the ranks meet: tcp://HOST:PORT (rank 0's address) or file://PATH (a new "
        "file on a filesystem all ranks share); MASTER_ADDR and MASTER_PORT when not given")
      ->type_name("URL");
  ts->add_option("--group-timeout", t.distributed.timeout_s,
                 "seconds a rank waits for the others, at the rendezvous and in every exchange")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// A training's DistributedOptions completed from the environment torchrun sets.
template <typename TrainOptions>
void CompleteFromEnvironment(TrainOptions& t) {
  t.distributed = DistributedOptionsFromEnvironment(t.distributed, DistributedEnvironment());
}

// Whether this process prints a training's summary: rank 0 (or the only process) does; the other
// ranks of a group trained the same model and say nothing.
template <typename TrainOptions>
bool PrintsSummary(const TrainOptions& t) {
  return t.distributed.rank == 0;
}

// The flags every `detect` command shares, bound to its options' DetectionRunOptions. Two groups,
// so that each command's own flags keep their place in its --help. This one: the model, the frames
// and the output folder (and det3d's --points, after --data, when `points_dir` is given).
void AddDetectInputFlags(CLI::App* ds, DetectionRunOptions& d,
                         std::filesystem::path* points_dir = nullptr) {
  ds->add_option("--model", d.model_dir, "model folder")->required();
  ds->add_option("--data", d.data_root, "dataset root")->required();
  if (points_dir != nullptr) {
    ds->add_option("--points", *points_dir,
                   "stereo models: the folder `stereodet stereo --encode points` wrote");
  }
  ds->add_option("--subset", d.subset, "training or testing")
      ->check(CLI::IsMember({"training", "testing"}))
      ->capture_default_str();
  ds->add_option("--split", d.split, "split name in ImageSets/ or a split file")
      ->capture_default_str();
  ds->add_option("--out", d.out_dir,
                 "folder for ID.txt detection files and run.json (one run: replaced whole)")
      ->required();
}

// The image families' --blur-sigma (the network's image only).
void AddBlurOption(CLI::App* ds, double* blur_sigma_px) {
  ds->add_option("--blur-sigma", *blur_sigma_px,
                 "Gaussian blur of the network's image, px (stereo stays sharp); 0 = none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
}

// The other group: batch size, threads, device and frame limit.
void AddDetectRunFlags(CLI::App* ds, DetectionRunOptions& d) {
  ds->add_option("--batch-size", d.batch_size, "frames per forward pass")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ds->add_option("--threads", d.threads, "threads (0 = all cores)")->capture_default_str();
  ds->add_option("--device", d.device, "cpu or cuda")
      ->check(CLI::IsMember({"cpu", "cuda"}))
      ->capture_default_str();
  ds->add_option("--max-frames", d.max_frames, "only the first N frames (0 = all)")
      ->capture_default_str();
  ds->add_option("--calibration", d.calibration,
                 "a score calibration file of `stereodet calibrate --fit`: the detections are "
                 "written with their calibrated probabilities (docs/metrics.md, Calibrators)");
}

// Warns (stderr, even with --quiet: it changes what the detections mean) when the model's
// training stopped before its last epoch.
void WarnIfTrainingUnfinished(const std::filesystem::path& model_dir) {
  const std::string warning = UnfinishedTrainingWarning(model_dir);
  if (!warning.empty()) std::fputs(warning.c_str(), stderr);
}

// The closing line of `detect ssd|rpn|det3d` (stderr; nothing with --quiet), and the time of each
// stage after it with --verbose.
void PrintDetectSummary(const DetectSummary& s, const std::filesystem::path& out_dir, bool quiet,
                        bool verbose) {
  if (quiet) return;
  std::fprintf(stderr, "detected %lld objects in %d frames, %.1f frames/s; wrote %s\n",
               static_cast<long long>(s.detections), s.frames, s.frames_per_second,
               out_dir.c_str());
  if (verbose) std::fputs(s.stage_times.c_str(), stderr);
}

// Runs a `detect` command: the warning for an unfinished model, then `detect(options)` (DetectSsd,
// DetectRpn, DetectDet3d; a family may complete its options there first) with this process's
// command line, then the closing line.
template <typename DetectOptions, typename Detect>
void RunDetectCommand(DetectCommandArgs<DetectOptions>& a, Detect detect) {
  WarnIfTrainingUnfinished(a.options.model_dir);
  if (a.quiet) a.options.progress.stream = nullptr;
  a.options.command_line = ProcessCommandLine();
  PrintDetectSummary(detect(a.options), a.options.out_dir, a.quiet, a.verbose);
}

// The last flags of every `detect` command: --shard, --quiet, --verbose.
template <typename DetectOptions>
void AddDetectOutputFlags(CLI::App* ds, DetectCommandArgs<DetectOptions>& a) {
  AddShardOption(ds, &a.options.shard);
  ds->add_flag("--quiet", a.quiet, "no progress or summary output");
  ds->add_flag("--verbose", a.verbose, "after the summary line, the time each stage took");
}

// Runs a `train` command: `train(options)` (TrainSsd, TrainRpn, TrainDet3d) with this process's
// command line and the training group of the environment (torchrun), then, unless quiet and on
// rank 0 alone, `print(summary)`.
template <typename TrainOptions, typename Train, typename Print>
void RunTrainCommand(TrainOptions& options, bool quiet, Train train, Print print) {
  if (quiet) options.progress.stream = nullptr;
  options.command_line = ProcessCommandLine();
  CompleteFromEnvironment(options);
  const auto summary = train(options);
  if (!quiet && PrintsSummary(options)) print(summary);
}

void RunTrain(TrainArgs& a) {
  TrainSsdOptions& options = a.options;
  const auto encoding = ParseInputEncoding(a.input);
  STEREODET_CHECK(encoding.has_value())
      << "unknown input encoding '" << a.input << "' (expected rgb, rgbh-fixed or rgbh-learned)";
  options.model.encoding = *encoding;
  const std::filesystem::path saved = options.out_dir / "model.json";
  if (AnyGiven(a.stereo_flags) && !UsesHeight(options.model.encoding)) {
    std::fprintf(stderr, "warning: an rgb model uses no stereo: %s ignored\n",
                 GivenFlagNames(a.stereo_flags).c_str());
  }
  if (options.resume && std::filesystem::exists(saved)) {
    // Partial stereo flags change only what they name of the settings the model was trained with.
    const std::optional<StereoOptions> recorded = ModelStereoSettings(options.out_dir);
    options.data.stereo = ApplyGivenStereoFlags(a.stereo_flags, recorded.value_or(StereoOptions()),
                                                options.data.stereo, a.stereo);
  } else {
    FinishStereoFlags(a.stereo, options.data.stereo);
    // A new RGB-H training matches at the network's scale unless --match-scale says otherwise.
    bool scale_given = false;
    for (const CLI::Option* flag : a.stereo_flags) {
      if (flag->get_name() == "--match-scale" && flag->count() > 0) scale_given = true;
    }
    options.auto_match_scale = !scale_given;
  }
  options.data.threads = options.threads;
  RunTrainCommand(options, a.quiet, TrainSsd, [&](const TrainSsdSummary& s) {
    std::fprintf(
        stderr,
        "trained %s: %d frames, epochs %d/%d (%d this run), final loss %.4f, %.1f images/s,"
        " %.0f s (stereo %.0f s); %lld parameters (%lld in the learned compression)\n"
        "model: %s\n",
        a.input.c_str(), s.frames, s.epochs_done, options.epochs, s.epochs_run, s.final_loss,
        s.frames_per_second, s.seconds, s.stereo_seconds, static_cast<long long>(s.parameters),
        static_cast<long long>(s.compression_parameters), options.out_dir.c_str());
  });
}

// The stereo flags given to `detect ssd`, applied to the RGB-H model's settings (partial flags
// change only what they name), with a warning when the model is rgb or they differ from its
// settings.
void ApplyStereoFlags(DetectArgs& a, DetectSsdOptions& options) {
  if (AnyGiven(a.stereo_flags)) {
    const std::optional<StereoOptions> recorded = ModelStereoSettings(options.model_dir);
    if (!recorded) {
      std::fprintf(stderr, "warning: %s is an rgb model, which uses no stereo: %s ignored\n",
                   options.model_dir.c_str(), GivenFlagNames(a.stereo_flags).c_str());
    } else {
      // Partial stereo flags change only what they name of the model's settings.
      options.stereo = ApplyGivenStereoFlags(a.stereo_flags, *recorded, a.stereo, a.stereo_text);
    }
    const std::string mismatch = StereoMismatch(options);
    if (!mismatch.empty()) {
      std::fprintf(stderr,
                   "warning: the stereo flags differ from the settings %s/model.json was trained "
                   "with: %s; using the flags\n",
                   options.model_dir.c_str(), mismatch.c_str());
    }
  }
}

// `detect ssd`: the stereo flags applied, then DetectSsd.
void RunDetect(DetectArgs& a) {
  RunDetectCommand(a, [&a](DetectSsdOptions& options) {
    ApplyStereoFlags(a, options);
    return DetectSsd(options);
  });
}

struct TrainDet3dArgs {
  TrainDet3dOptions options;
  std::string input = PointSourceName(Det3dConfig().input);
  bool quiet = false;
};

using DetectDet3dArgs = DetectCommandArgs<DetectDet3dOptions>;

void RunTrainDet3d(TrainDet3dArgs& a) {
  TrainDet3dOptions& options = a.options;
  options.model.input = *ParsePointSource(a.input);  // CLI::IsMember checked it
  RunTrainCommand(options, a.quiet, TrainDet3d, [&](const TrainDet3dSummary& s) {
    std::fprintf(stderr,
                 "trained det3d on %s: %d frames (%d objects, %lld in the GT database with %lld "
                 "points), epochs "
                 "%d/%d (%d this run), final "
                 "loss %.4f, %.2f frames/s, %.3f s/step, %.0f s; %lld parameters (%lld in the "
                 "auxiliary network, training only)\nmodel: %s\n",
                 a.input.c_str(), s.frames, s.objects,
                 static_cast<long long>(s.gt_database_objects),
                 static_cast<long long>(s.gt_database_points), s.epochs_done, options.epochs,
                 s.epochs_run, s.final_loss, s.frames_per_second, s.seconds_per_step, s.seconds,
                 static_cast<long long>(s.parameters),
                 static_cast<long long>(s.auxiliary_parameters), options.out_dir.c_str());
  });
}

void AddDet3dCommands(CLI::App* train, CLI::App* detect) {
  auto targs = std::make_shared<TrainDet3dArgs>();
  TrainDet3dOptions& t = targs->options;
  CLI::App* ts = train->add_subcommand(
      "det3d",
      "single-stage 3D detector (pillars, BEV CNN, SA-SSD auxiliary net, PSWarp) on "
      "lidar scans or stereo point clouds");
  AddTrainingDataFlags(ts, t, &t.points_dir);
  ts->add_option("--input", targs->input, "point source")
      ->check(CLI::IsMember({"lidar", "stereo"}))
      ->capture_default_str();
  AddTrainingFlags(ts, t);
  ts->add_option("--width", t.model.base_channels, "base channels of the BEV backbone")
      ->capture_default_str();
  ts->add_option("--pillar", t.model.grid.pillar_m, "pillar size, m")->capture_default_str();
  ts->add_option("--max-distance", t.filter.stereo_max_distance_m,
                 "stereo: drop points farther than this, m (0 = keep all)")
      ->capture_default_str();
  ts->add_flag("!--no-augment", t.augment.enabled, "no augmentation (flip, noise)");
  ts->add_flag("!--no-gt-sampling", t.gt_sampling.enabled,
               "no GT-database cut-and-paste (objects of other training frames)");
  ts->add_option("--gt-per-class", t.gt_sampling.max_per_class,
                 "GT sampling: objects drawn per class and frame, pasted unless they collide")
      ->capture_default_str();
  ts->add_option("--gt-min-points", t.gt_database.min_points,
                 "GT database: leave out objects with fewer points")
      ->capture_default_str();
  ts->add_flag("!--no-auxiliary", t.loss.auxiliary, "do not train the auxiliary network");
  AddTrainingStopFlags(ts, t);
  ts->add_flag("--quiet", targs->quiet, "no progress or summary output");
  ts->callback([targs] { RunTrainDet3d(*targs); });

  auto dargs = std::make_shared<DetectDet3dArgs>();
  DetectDet3dOptions& d = dargs->options;
  CLI::App* ds = detect->add_subcommand("det3d", "run a model from `stereodet train det3d`");
  AddDetectInputFlags(ds, d, &d.points_dir);
  ds->add_option("--score-threshold", d.decode.score_threshold, "drop detections scoring below")
      ->capture_default_str();
  ds->add_option("--max-distance", d.filter.stereo_max_distance_m,
                 "stereo: drop points farther than this, m (0 = keep all)")
      ->capture_default_str();
  AddDetectRunFlags(ds, d);
  AddDetectOutputFlags(ds, *dargs);
  ds->callback([dargs] { RunDetectCommand(*dargs, DetectDet3d); });
}

struct DetectMergeArgs {
  MergeDetectionsOptions options;
  bool quiet = false;
};

void AddDetectMergeCommand(CLI::App* detect) {
  auto args = std::make_shared<DetectMergeArgs>();
  MergeDetectionsOptions& m = args->options;
  CLI::App* cmd = detect->add_subcommand(
      "merge",
      "combine the folders of `detect ssd|det3d|rpn --shard K/N --out DIR` (all N) into the "
      "detection folder of one run, byte for byte (docs/scale.md)");
  cmd->add_option("shards", m.shards, "the shard folders, in any order")->required();
  cmd->add_option("--out", m.out_dir, "the detection folder (one run: replaced whole)")->required();
  cmd->add_flag("--quiet", args->quiet, "no summary output");
  cmd->callback([args] {
    args->options.command_line = ProcessCommandLine();
    const MergeDetectionsResult r = MergeDetections(args->options);
    if (!args->quiet) {
      std::fprintf(stderr, "merged %d shards of %s, %d frames, in %.2f s; wrote %s\n", r.shards,
                   r.tool.c_str(), r.frames, r.seconds, args->options.out_dir.c_str());
    }
  });
}

struct TrainRpnArgs {
  TrainRpnOptions options;
  std::string input = RpnInputName(RpnConfig().input);
  StereoFlagText stereo;  // the stereo flags, bound to options.data.stereo (rgbd)
  bool quiet = false;
};

using DetectRpnArgs = DetectCommandArgs<DetectRpnOptions>;

void RunTrainRpn(TrainRpnArgs& a) {
  TrainRpnOptions& options = a.options;
  options.model.input = *ParseRpnInput(a.input);  // CLI::IsMember checked it
  options.model.anchors.stride_px = options.model.feature_stride;
  FinishStereoFlags(a.stereo, options.data.stereo);
  options.data.threads = options.threads;
  RunTrainCommand(options, a.quiet, TrainRpn, [&](const TrainRpnSummary& s) {
    std::fprintf(
        stderr,
        "trained rpn on %s: %d frames (%d objects), epochs %d/%d (%d this run), final "
        "loss %.4f, %.2f images/s, %.3f s/step, %.0f s (labels/stereo %.0f s); %lld "
        "parameters (image branch %lld, geometry branch %lld)%s\nmodel: %s\n",
        a.input.c_str(), s.frames, s.objects, s.epochs_done, options.epochs, s.epochs_run,
        s.final_loss, s.frames_per_second, s.seconds_per_step, s.seconds, s.stereo_seconds,
        static_cast<long long>(s.parameters), static_cast<long long>(s.image_branch_parameters),
        static_cast<long long>(s.geometry_branch_parameters),
        s.init_tensors > 0
            ? fmt::format("; {} tensors from {}", s.init_tensors, options.init_from.string())
                  .c_str()
            : "",
        options.out_dir.c_str());
  });
}

void AddRpnCommands(CLI::App* train, CLI::App* detect) {
  auto targs = std::make_shared<TrainRpnArgs>();
  TrainRpnOptions& t = targs->options;
  CLI::App* ts = train->add_subcommand(
      "rpn",
      "two-stage detector (ResNet-style trunks, region proposal network, RoIAlign box head) on "
      "rgb, or rgbd with a late-fused depth and height branch");
  AddTrainingDataFlags(ts, t);
  ts->add_option("--input", targs->input, "rgb (image branch) or rgbd (+ geometry branch)")
      ->check(CLI::IsMember({"rgb", "rgbd"}))
      ->capture_default_str();
  AddTrainingFlags(ts, t);
  ts->add_option("--width", t.model.input_width, "network input width, px (multiple of 16)")
      ->capture_default_str();
  ts->add_option("--height", t.model.input_height, "network input height, px (multiple of 16)")
      ->capture_default_str();
  ts->add_option("--image-width", t.model.image_width,
                 "base channels of the image branch (stages x1, x2, x4); widen an rgb model to "
                 "the rgbd model's parameter count as a control")
      ->capture_default_str();
  ts->add_option("--geometry-width", t.model.geometry_width,
                 "base channels of the geometry branch (rgbd)")
      ->capture_default_str();
  ts->add_option("--feature-stride", t.model.feature_stride,
                 "stride of the RPN's and RoIAlign's features: 16, or 8 for small objects")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  ts->add_option("--warmup", t.warmup_steps, "steps of the linear learning-rate warm-up")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  ts->add_option("--init-from", t.init_from,
                 "rgb model folder whose image branch, RPN and box head initialise this model "
                 "(\"mirroring\"; rgbd: the fusion starts as image features only)");
  ts->add_flag("--init-geometry", t.init_geometry,
               "with --init-from: mirror the image branch into the geometry branch too");
  ts->add_flag("!--no-augment", t.data.augment, "no augmentation (flip, colour jitter)");
  AddTrainingStopFlags(ts, t);
  AddStereoFlags(ts, t.data.stereo, targs->stereo);
  ts->add_flag("--quiet", targs->quiet, "no progress or summary output");
  ts->callback([targs] { RunTrainRpn(*targs); });

  auto dargs = std::make_shared<DetectRpnArgs>();
  DetectRpnOptions& d = dargs->options;
  CLI::App* ds = detect->add_subcommand("rpn", "run a model from `stereodet train rpn`");
  AddDetectInputFlags(ds, d);
  AddBlurOption(ds, &d.blur_sigma_px);
  ds->add_option("--score-threshold", d.detect.decode.score_threshold,
                 "drop detections scoring below")
      ->capture_default_str();
  ds->add_option("--proposals", d.detect.proposals.post_nms_top_n, "proposals per image after NMS")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  AddDetectRunFlags(ds, d);
  AddDetectOutputFlags(ds, *dargs);
  ds->callback([dargs] { RunDetectCommand(*dargs, DetectRpn); });
}

}  // namespace

void AddModelsCommand(CLI::App& app) {
  CLI::App* train = Group(app, "train");
  CLI::App* detect = Group(app, "detect");

  auto targs = std::make_shared<TrainArgs>();
  TrainSsdOptions& t = targs->options;
  CLI::App* ts = train->add_subcommand(
      "ssd", "single-shot image detector on rgb, rgbh-fixed or rgbh-learned input");
  AddTrainingDataFlags(ts, t);
  ts->add_option("--input", targs->input, "input encoding")
      ->check(CLI::IsMember({"rgb", "rgbh-fixed", "rgbh-learned"}))
      ->capture_default_str();
  AddTrainingFlags(ts, t);
  ts->add_option("--width", t.model.boxes.input_width, "network input width, px")
      ->capture_default_str();
  ts->add_option("--height", t.model.boxes.input_height, "network input height, px")
      ->capture_default_str();
  AddTrainingStopFlags(ts, t);
  targs->stereo_flags = AddStereoFlags(ts, t.data.stereo, targs->stereo);
  CLI::Option* train_stereo_dir = ts->add_option(
      "--stereo", t.data.stereo_dir,
      "RGB-H: read the heights from this `stereodet stereo` folder (its stereo.json's settings) "
      "instead of matching");
  for (CLI::Option* flag : targs->stereo_flags) train_stereo_dir->excludes(flag);
  ts->add_flag("--quiet", targs->quiet, "no progress or summary output");
  ts->callback([targs] { RunTrain(*targs); });

  auto dargs = std::make_shared<DetectArgs>();
  DetectSsdOptions& d = dargs->options;
  CLI::App* ds = detect->add_subcommand("ssd", "run a model from `stereodet train ssd`");
  AddDetectInputFlags(ds, d);
  AddBlurOption(ds, &d.blur_sigma_px);
  ds->add_option("--score-threshold", d.decode.score_threshold, "drop detections scoring below")
      ->capture_default_str();
  AddDetectRunFlags(ds, d);
  ds->add_flag("!--no-pipeline", d.pipeline,
               "prepare each batch (reading, stereo) only after the network's previous one "
               "(default: the next batch is prepared while the network runs; same detections)");
  dargs->stereo_flags = AddStereoFlags(ds, dargs->stereo, dargs->stereo_text);
  CLI::Option* detect_stereo_dir = ds->add_option(
      "--stereo", d.stereo_dir,
      "RGB-H: read the heights from this `stereodet stereo` folder instead of matching; refused "
      "when its stereo.json's settings differ from the model's");
  for (CLI::Option* flag : dargs->stereo_flags) detect_stereo_dir->excludes(flag);
  AddDetectOutputFlags(ds, *dargs);
  ds->callback([dargs] { RunDetect(*dargs); });

  AddDet3dCommands(train, detect);
  AddDetectMergeCommand(detect);
  AddRpnCommands(train, detect);
}

}  // namespace stereodet::cli
