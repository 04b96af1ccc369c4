#include "stereodet/models/rpn/rpn_train.h"

#include <fmt/format.h>

#include <cmath>

#include "stereodet/models/ssd_data.h"
#include "stereodet/models/train_common.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

namespace {

constexpr char kLogHeader[] =
    "epoch,steps,frames,loss,objectness_loss,rpn_box_loss,head_class_loss,head_box_loss,"
    "positive_anchors,foreground_rois,learning_rate,images_per_s,epoch_s";

// The seed of a step's anchor and RoI sampling (and of torch's generator): a function of the run's
// seed and the global step only, so a resumed run draws what an uninterrupted one draws.
uint64_t StepSeed(uint64_t seed, int64_t step) {
  return SampleSeed(seed ^ 0x52504e5f53544550ULL, static_cast<int>(step), -3);
}

}  // namespace

void TrainRpnOptions::Check() const {
  model.Check();
  data.Check();
  trainer.Check();
  CheckTrainingSchedule(*this);
  STEREODET_CHECK(!init_geometry || !init_from.empty()) << "--init-geometry needs --init-from";
}

TrainRpnSummary TrainRpn(const TrainRpnOptions& options) {
  options.Check();
  const ComputeDevice device = ResolveComputeDevice(options.device);
  const Timer total_timer;
  SetTorchThreads(options.threads);
  TrainRpnSummary summary;

  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, fs::path>> inputs = {
      {"--data", options.data_root / "training"}, {"--data", options.data_root / "ImageSets"}};
  if (!options.init_from.empty()) inputs.push_back({"--init-from", options.init_from});
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir, inputs);
  const OutputLock lock(options.out_dir);
  const bool resuming =
      PrepareModelFolder(options.out_dir, "train rpn", options.resume, options.force);
  const fs::path config_path = options.out_dir / "model.json";
  const fs::path checkpoint_path = options.out_dir / kCheckpointFile;
  RpnConfig config = options.model;
  RpnDataOptions data_options = options.data;
  if (resuming) {
    const std::string text = ReadFile(config_path);
    const RpnConfig saved = RpnConfigFromJson(text, config_path.string());
    STEREODET_CHECK(saved.input == config.input)
        << "--resume: " << config_path.string() << " was trained with --input "
        << RpnInputName(saved.input) << ", not " << RpnInputName(config.input);
    config = saved;
    // The geometry the model was trained on so far, whatever the flags say now.
    if (config.input == RpnInput::kRgbd) {
      data_options.stereo = ReadRpnStereoRecord(text, config_path.string());
    }
  }

  const KittiDataset dataset(options.data_root, "training");
  std::vector<std::string> ids = dataset.ReadSplit(options.split);
  if (options.max_frames > 0 && static_cast<int>(ids.size()) > options.max_frames) {
    ids.resize(options.max_frames);
  }
  STEREODET_CHECK(!ids.empty()) << "split '" << options.split << "' has no frames";

  RpnModel model(config, options.seed, device);
  model.set_stereo(data_options.stereo);
  if (!resuming && !options.init_from.empty()) {
    const RpnModel rgb = RpnModel::Load(options.init_from, device);
    summary.init_tensors = model.InitFrom(rgb, options.init_geometry);
  }
  RpnTrainer trainer(model, options.trainer);
  summary.parameters = model.ParameterCount();
  summary.image_branch_parameters = model.ImageBranchParameterCount();
  summary.geometry_branch_parameters = model.GeometryBranchParameterCount();
  const int start_epoch = resuming ? trainer.LoadCheckpoint(checkpoint_path) : 0;
  STEREODET_CHECK(start_epoch >= 0) << "bad epoch count in " << checkpoint_path.string();
  summary.epochs_done = start_epoch;
  if (start_epoch >= options.epochs) {
    summary.seconds = total_timer.ElapsedSeconds();
    return summary;
  }

  const Timer stereo_timer;
  const RpnTrainingData data(dataset, ids, config, data_options, options.progress);
  summary.stereo_seconds = stereo_timer.ElapsedSeconds();
  summary.frames = data.size();
  summary.objects = data.NumObjects();

  RunManifest manifest;
  manifest.tool = "train rpn";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"data", options.data_root.string()}, {"split", options.split}};
  if (!options.init_from.empty()) {
    manifest.inputs.push_back({"init_from", options.init_from.string()});
  }
  auto write_manifest = [&](int epochs_done) {
    manifest.settings_json = fmt::format(
        R"({{"input": "{}", "epochs": {}, "epochs_done": {}, "batch_size": {}, )"
        R"("learning_rate": {}, "warmup_steps": {}, "final_lr_fraction": {}, "seed": {}, )"
        R"("max_frames": {}, "frames": {}, "input_width": {}, "input_height": {}, )"
        R"("image_width": {}, "geometry_width": {}, "threads": {}, "device": "{}", )"
        R"("augment": {}, "init_from": "{}", "init_geometry": {}, "parameters": {}}})",
        RpnInputName(config.input), options.epochs, epochs_done, options.batch_size,
        options.learning_rate, options.warmup_steps, options.final_lr_fraction, options.seed,
        options.max_frames, ids.size(), config.input_width, config.input_height, config.image_width,
        config.geometry_width, options.threads, options.device, options.data.augment,
        options.init_from.string(), options.init_geometry, summary.parameters);
    WriteRunManifest(options.out_dir, manifest);
  };
  write_manifest(start_epoch);
  const fs::path log_path = options.out_dir / kTrainLogFile;
  std::string log = KeptLogLines(log_path, kLogHeader, start_epoch);

  const int n = data.size();
  const int64_t steps_per_epoch = (n + options.batch_size - 1) / options.batch_size;
  const int64_t total_steps = steps_per_epoch * options.epochs;
  const int end_epoch = options.max_epochs_this_run > 0
                            ? std::min(options.epochs, start_epoch + options.max_epochs_this_run)
                            : options.epochs;
  double train_seconds = 0;
  int64_t frames_trained = 0, steps_trained = 0;
  for (int epoch = start_epoch; epoch < end_epoch; ++epoch) {
    const Timer epoch_timer;
    const std::vector<int> order = EpochOrder(n, options.seed, epoch);
    ProgressReporter progress(fmt::format("epoch {}/{}", epoch + 1, options.epochs), n,
                              options.progress);
    RpnLossParts sum;
    double lr = 0;
    int64_t step = epoch * steps_per_epoch;
    int steps = 0, done = 0;
    for (int begin = 0; begin < n; begin += options.batch_size) {
      const int end = std::min(n, begin + options.batch_size);
      // The batch in order: each sample into its own slot, from its own seed.
      std::vector<RpnSample> samples(end - begin);
      ParallelFor(
          samples.size(),
          [&](size_t k) {
            const int index = order[begin + k];
            samples[k] = data.Sample(index, SampleSeed(options.seed, epoch, index));
          },
          options.threads);
      RpnBatch batch;
      for (RpnSample& s : samples) {
        batch.inputs.push_back(std::move(s.input));
        batch.objects.push_back(std::move(s.objects));
      }
      lr = WarmupCosineLearningRate(options.learning_rate, options.warmup_steps,
                                    options.final_lr_fraction, step, total_steps);
      const RpnLossParts loss = trainer.Step(batch, lr, StepSeed(options.seed, step));
      STEREODET_CHECK_IO(std::isfinite(loss.total))
          << "training diverged at epoch " << epoch + 1 << ", step " << step << " (loss "
          << loss.total << "); try a lower --lr";
      sum.total += loss.total;
      sum.objectness += loss.objectness;
      sum.rpn_box += loss.rpn_box;
      sum.head_class += loss.head_class;
      sum.head_box += loss.head_box;
      sum.positive_anchors += loss.positive_anchors;
      sum.foreground_rois += loss.foreground_rois;
      ++steps;
      ++step;
      done += end - begin;
      progress.Add(end - begin,
                   fmt::format("loss {:.3f} (obj {:.3f} rpn-box {:.3f} cls {:.3f} box {:.3f})",
                               sum.total / steps, sum.objectness / steps, sum.rpn_box / steps,
                               sum.head_class / steps, sum.head_box / steps));
    }
    progress.Finish();
    const double epoch_seconds = epoch_timer.ElapsedSeconds();
    train_seconds += epoch_seconds;
    frames_trained += done;
    steps_trained += steps;
    model.Save(options.out_dir);
    trainer.SaveCheckpoint(checkpoint_path, epoch + 1);
    log += fmt::format("{},{},{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{},{},{:.6g},{:.3f},{:.1f}\n",
                       epoch + 1, steps, done, sum.total / steps, sum.objectness / steps,
                       sum.rpn_box / steps, sum.head_class / steps, sum.head_box / steps,
                       sum.positive_anchors, sum.foreground_rois, lr, done / epoch_seconds,
                       epoch_seconds);
    WriteFileAtomically(log_path, log);
    write_manifest(epoch + 1);
    summary.epochs_done = epoch + 1;
    ++summary.epochs_run;
    summary.final_loss = sum.total / steps;
  }
  summary.images_per_second = train_seconds > 0 ? frames_trained / train_seconds : 0;
  summary.seconds_per_step = steps_trained > 0 ? train_seconds / steps_trained : 0;
  summary.seconds = total_timer.ElapsedSeconds();
  return summary;
}

}  // namespace stereodet
