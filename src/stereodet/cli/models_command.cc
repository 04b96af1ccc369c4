// `stereodet train ssd` and `stereodet detect ssd`: the single-shot image detector (issue 6).
//   stereodet train ssd --data DIR --split train --input rgb|rgbh-fixed|rgbh-learned --out
//   MODEL_DIR
//                       [--epochs N] [--resume] [--seed S] [--threads N] [--width W --height H]
//   stereodet detect ssd --model MODEL_DIR --data DIR --split val --out DIR [--blur-sigma S]
#include <fmt/format.h>

#include <cstdio>
#include <memory>
#include <string>

#include "stereodet/cli/commands.h"
#include "stereodet/models/ssd.h"
#include "stereodet/models/ssd_detect.h"
#include "stereodet/models/ssd_train.h"
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

struct TrainArgs {
  std::string data, split = "train", input = "rgb", out;
  int epochs = 10, batch_size = 8, width = 621, height = 188, threads = 0, max_frames = 0;
  int stop_after = 0;
  double lr = 2e-3;
  uint64_t seed = 1;
  bool resume = false, quiet = false;
};

struct DetectArgs {
  std::string model, data, subset = "training", split = "val", out;
  double blur_sigma = 0.0, score_threshold = 0.01;
  int threads = 0, batch_size = 8, max_frames = 0;
  bool quiet = false;
};

void RunTrain(const TrainArgs& a) {
  TrainSsdOptions options;
  options.data_root = a.data;
  options.split = a.split;
  options.out_dir = a.out;
  const auto encoding = ParseInputEncoding(a.input);
  STEREODET_CHECK(encoding.has_value())
      << "unknown input encoding '" << a.input << "' (expected rgb, rgbh-fixed or rgbh-learned)";
  options.model.encoding = *encoding;
  options.model.boxes.input_width = a.width;
  options.model.boxes.input_height = a.height;
  options.epochs = a.epochs;
  options.batch_size = a.batch_size;
  options.learning_rate = a.lr;
  options.seed = a.seed;
  options.resume = a.resume;
  options.threads = a.threads;
  options.max_frames = a.max_frames;
  options.max_epochs_this_run = a.stop_after;
  options.data.threads = a.threads;
  if (a.quiet) options.progress.stream = nullptr;
  const TrainSsdSummary s = TrainSsd(options);
  if (!a.quiet) {
    std::fprintf(
        stderr,
        "trained %s: %d frames, epochs %d/%d (%d this run), final loss %.4f, %.1f images/s,"
        " %.0f s (stereo %.0f s); %lld parameters (%lld in the learned compression)\n"
        "model: %s\n",
        a.input.c_str(), s.frames, s.epochs_done, a.epochs, s.epochs_run, s.final_loss,
        s.images_per_second, s.seconds, s.stereo_seconds, static_cast<long long>(s.parameters),
        static_cast<long long>(s.compression_parameters), a.out.c_str());
  }
}

void RunDetect(const DetectArgs& a) {
  DetectSsdOptions options;
  options.model_dir = a.model;
  options.data_root = a.data;
  options.subset = a.subset;
  options.split = a.split;
  options.out_dir = a.out;
  options.blur_sigma_px = a.blur_sigma;
  options.batch_size = a.batch_size;
  options.threads = a.threads;
  options.max_frames = a.max_frames;
  options.decode.score_threshold = static_cast<float>(a.score_threshold);
  if (a.quiet) options.progress.stream = nullptr;
  const DetectSsdSummary s = DetectSsd(options);
  if (!a.quiet) {
    std::fprintf(stderr, "detected %lld objects in %d frames, %.1f images/s; wrote %s\n%s",
                 static_cast<long long>(s.detections), s.frames, s.images_per_second, a.out.c_str(),
                 s.stage_times.c_str());
  }
}

}  // namespace

void AddModelsCommand(CLI::App& app) {
  CLI::App* train = Group(app, "train");
  CLI::App* detect = Group(app, "detect");

  auto targs = std::make_shared<TrainArgs>();
  CLI::App* ts = train->add_subcommand(
      "ssd", "single-shot image detector on rgb, rgbh-fixed or rgbh-learned input");
  ts->add_option("--data", targs->data, "dataset root (training/, ImageSets/)")->required();
  ts->add_option("--split", targs->split, "split name in ImageSets/ or a split file")
      ->capture_default_str();
  ts->add_option("--input", targs->input, "input encoding")
      ->check(CLI::IsMember({"rgb", "rgbh-fixed", "rgbh-learned"}))
      ->capture_default_str();
  ts->add_option("--out", targs->out, "model folder (model.json, model.pt, checkpoint, log)")
      ->required();
  ts->add_option("--epochs", targs->epochs, "epochs")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ts->add_option("--batch-size", targs->batch_size, "frames per step")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ts->add_option("--lr", targs->lr, "peak learning rate (AdamW, warm-up then cosine)")
      ->capture_default_str();
  ts->add_flag("--resume", targs->resume, "continue from MODEL_DIR/checkpoint.pt if present");
  ts->add_option("--seed", targs->seed, "seed of weights, data order, augmentation")
      ->capture_default_str();
  ts->add_option("--threads", targs->threads, "threads (0 = all cores)")->capture_default_str();
  ts->add_option("--width", targs->width, "network input width, px")->capture_default_str();
  ts->add_option("--height", targs->height, "network input height, px")->capture_default_str();
  ts->add_option("--max-frames", targs->max_frames, "use only the first N frames (0 = all)")
      ->capture_default_str();
  ts->add_option("--stop-after", targs->stop_after,
                 "stop after N epochs in this run (0 = all); continue later with --resume")
      ->capture_default_str();
  ts->add_flag("--quiet", targs->quiet, "no progress or summary output");
  ts->callback([targs] { RunTrain(*targs); });

  auto dargs = std::make_shared<DetectArgs>();
  CLI::App* ds = detect->add_subcommand("ssd", "run a model from `stereodet train ssd`");
  ds->add_option("--model", dargs->model, "model folder")->required();
  ds->add_option("--data", dargs->data, "dataset root")->required();
  ds->add_option("--subset", dargs->subset, "training or testing")
      ->check(CLI::IsMember({"training", "testing"}))
      ->capture_default_str();
  ds->add_option("--split", dargs->split, "split name in ImageSets/ or a split file")
      ->capture_default_str();
  ds->add_option("--out", dargs->out, "folder for ID.txt detection files")->required();
  ds->add_option("--blur-sigma", dargs->blur_sigma,
                 "Gaussian blur of the network's image, px (stereo stays sharp); 0 = none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  ds->add_option("--score-threshold", dargs->score_threshold, "drop detections scoring below")
      ->capture_default_str();
  ds->add_option("--batch-size", dargs->batch_size, "frames per forward pass")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  ds->add_option("--threads", dargs->threads, "threads (0 = all cores)")->capture_default_str();
  ds->add_option("--max-frames", dargs->max_frames, "only the first N frames (0 = all)")
      ->capture_default_str();
  ds->add_flag("--quiet", dargs->quiet, "no progress or summary output");
  ds->callback([dargs] { RunDetect(*dargs); });
}

}  // namespace stereodet::cli
