#include "stereodet/models/det3d/det3d_train.h"

#include <fmt/format.h>

#include <cmath>

#include "stereodet/models/det3d/gt_database.h"
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
    "epoch,steps,frames,loss,classification_loss,box_loss,direction_loss,part_warp_loss,"
    "segmentation_loss,centre_loss,learning_rate,frames_per_s,epoch_s";

}  // namespace

void TrainDet3dOptions::Check() const {
  model.Check();
  filter.Check();
  augment.Check();
  gt_database.Check();
  gt_sampling.Check();
  loss.Check();
  CheckTrainingSchedule(*this);
  STEREODET_CHECK(model.input != PointSource::kStereo || !points_dir.empty())
      << "--input stereo needs --points (the folder `stereodet stereo --encode points` wrote)";
  STEREODET_CHECK(weight_decay >= 0.0 && std::isfinite(weight_decay))
      << "weight decay must be >= 0, got " << weight_decay;
  STEREODET_CHECK(max_aux_points >= 0) << "max_aux_points must be >= 0, got " << max_aux_points;
}

TrainDet3dSummary TrainDet3d(const TrainDet3dOptions& options) {
  options.Check();
  const ComputeDevice device = ResolveComputeDevice(options.device);
  const Timer total_timer;
  SetTorchThreads(options.threads);
  TrainDet3dSummary summary;

  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, fs::path>> inputs = {
      {"--data", options.data_root / "training"}, {"--data", options.data_root / "ImageSets"}};
  if (!options.points_dir.empty()) inputs.push_back({"--points", options.points_dir});
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir, inputs);
  const OutputLock lock(options.out_dir);
  const bool resuming =
      PrepareModelFolder(options.out_dir, "train det3d", options.resume, options.force);
  const fs::path config_path = options.out_dir / "model.json";
  const fs::path checkpoint_path = options.out_dir / kCheckpointFile;
  Det3dConfig config = options.model;
  std::string recorded_run;  // ties model.json to checkpoint.pt (train_common.h)
  if (resuming) {
    const std::string saved_text = ReadFile(config_path);
    recorded_run = ReadWeightsRecord(saved_text, config_path.string()).training_run;
    const Det3dConfig saved = Det3dConfigFromJson(saved_text, config_path.string());
    STEREODET_CHECK(saved.input == config.input)
        << "--resume: " << config_path.string() << " was trained with --input "
        << PointSourceName(saved.input) << ", not " << PointSourceName(config.input);
    config = saved;
  }

  const KittiDataset dataset(options.data_root, "training");
  std::vector<std::string> ids = dataset.ReadSplit(options.split);
  if (options.max_frames > 0 && static_cast<int>(ids.size()) > options.max_frames) {
    ids.resize(options.max_frames);
  }
  STEREODET_CHECK(!ids.empty()) << "split '" << options.split << "' has no frames";

  Det3dModel model(config, options.seed, device);
  Det3dTrainer trainer(model, options.loss, options.weight_decay);
  summary.parameters = model.ParameterCount();
  summary.auxiliary_parameters = model.AuxiliaryParameterCount();
  const int start_epoch = resuming ? trainer.LoadCheckpoint(checkpoint_path, recorded_run) : 0;
  const std::string training_run = recorded_run.empty() ? NewTrainingRunId() : recorded_run;
  STEREODET_CHECK(start_epoch >= 0) << "bad epoch count in " << checkpoint_path.string();
  summary.epochs_done = start_epoch;
  if (start_epoch >= options.epochs) {
    summary.seconds = total_timer.ElapsedSeconds();
    return summary;
  }

  // Every frame in memory once (points and boxes); augmentation works on copies.
  std::vector<Det3dFrame> frames(ids.size());
  {
    ProgressReporter progress("load", static_cast<int64_t>(ids.size()), options.progress);
    ParallelFor(
        ids.size(),
        [&](size_t i) {
          frames[i] = LoadDet3dFrame(dataset, options.points_dir, config.input, ids[i],
                                     config.classes, config.grid, options.filter,
                                     /*with_labels=*/true);
        },
        options.threads);
    progress.Add(static_cast<int64_t>(ids.size()));
  }
  summary.frames = static_cast<int>(frames.size());
  for (const Det3dFrame& f : frames) summary.objects += static_cast<int>(f.boxes.size());
  // GT-database sampling: the objects of these very frames, so of the model's input only.
  const bool gt_sampling = options.augment.enabled && options.gt_sampling.enabled;
  GtDatabase gt_database;
  if (gt_sampling) {
    gt_database = BuildGtDatabase(frames, static_cast<int>(config.classes.size()), config.input,
                                  options.gt_database);
  }
  summary.gt_database_objects = gt_database.ObjectCount();
  summary.gt_database_points = gt_database.PointCount();

  RunManifest manifest;
  manifest.tool = "train det3d";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"data", options.data_root.string()}, {"split", options.split}};
  if (!options.points_dir.empty())
    manifest.inputs.push_back({"points", options.points_dir.string()});
  auto write_manifest = [&](int epochs_done) {
    manifest.settings_json = fmt::format(
        R"({{"input": "{}", "epochs": {}, "epochs_done": {}, "batch_size": {}, )"
        R"("learning_rate": {}, "warmup_steps": {}, "final_lr_fraction": {}, "seed": {}, )"
        R"("max_frames": {}, "frames": {}, "base_channels": {}, "pillar_m": {}, "device": "{}", )"
        R"("augment": {}, "auxiliary": {}, "stereo_max_distance_m": {}, "camera_fov_only": {}, )"
        R"("crop_to_grid": {}, "gt_sampling": {}, "gt_per_class": {}, "gt_min_points": {}, )"
        R"("gt_box_margin_m": {}, "gt_database_objects": {}}})",
        PointSourceName(config.input), options.epochs, epochs_done, options.batch_size,
        options.learning_rate, options.warmup_steps, options.final_lr_fraction, options.seed,
        options.max_frames, ids.size(), config.base_channels, config.grid.pillar_m, options.device,
        options.augment.enabled, options.loss.auxiliary, options.filter.stereo_max_distance_m,
        options.filter.camera_fov_only, options.filter.crop_to_grid, gt_sampling,
        options.gt_sampling.max_per_class, options.gt_database.min_points,
        options.gt_database.box_margin_m, gt_database.ObjectCount());
    WriteRunManifest(options.out_dir, manifest);
  };
  write_manifest(start_epoch);
  const fs::path log_path = options.out_dir / kTrainLogFile;
  std::string log = KeptLogLines(log_path, kLogHeader, start_epoch);

  const int n = static_cast<int>(frames.size());
  const int64_t steps_per_epoch = (n + options.batch_size - 1) / options.batch_size;
  const int64_t total_steps = steps_per_epoch * options.epochs;
  if (const std::string warning =
          WarmupWarning(options.warmup_steps, steps_per_epoch, options.epochs);
      !warning.empty() && options.progress.stream != nullptr) {
    std::fputs(warning.c_str(), options.progress.stream);
  }
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
    Det3dLossParts sum;
    double lr = 0;
    int64_t step = epoch * steps_per_epoch;
    int steps = 0, done = 0;
    for (int begin = 0; begin < n; begin += options.batch_size) {
      const int end = std::min(n, begin + options.batch_size);
      std::vector<Det3dSample> batch(end - begin);
      ParallelFor(
          batch.size(),
          [&](size_t k) {
            const int index = order[begin + k];
            // GT sampling draws from ~seed: a stream apart from AugmentFrame's, both fixed by
            // (seed, epoch, frame), so a resumed training samples the same objects.
            const uint64_t seed = SampleSeed(options.seed, epoch, index);
            const Det3dFrame augmented =
                gt_sampling ? AugmentFrame(SampleGtObjects(frames[index], gt_database,
                                                           options.gt_sampling, ~seed)
                                               .frame,
                                           options.augment, seed)
                            : AugmentFrame(frames[index], options.augment, seed);
            batch[k] =
                MakeDet3dSample(augmented, config, model.anchors(), true, options.max_aux_points);
          },
          options.threads);
      lr = WarmupCosineLearningRate(options.learning_rate, options.warmup_steps,
                                    options.final_lr_fraction, step, total_steps);
      const Det3dLossParts loss = trainer.Step(batch, lr);
      STEREODET_CHECK_IO(std::isfinite(loss.total))
          << "training diverged at epoch " << epoch + 1 << ", step " << step << " (loss "
          << loss.total << "); try a lower --lr";
      sum.total += loss.total;
      sum.classification += loss.classification;
      sum.box += loss.box;
      sum.direction += loss.direction;
      sum.part_warp += loss.part_warp;
      sum.segmentation += loss.segmentation;
      sum.centre += loss.centre;
      ++steps;
      ++step;
      done += end - begin;
      progress.Add(end - begin, fmt::format("loss {:.3f} (cls {:.3f} box {:.3f} psw {:.3f} "
                                            "seg {:.3f} ctr {:.3f})",
                                            sum.total / steps, sum.classification / steps,
                                            sum.box / steps, sum.part_warp / steps,
                                            sum.segmentation / steps, sum.centre / steps));
    }
    progress.Finish();
    const double epoch_seconds = epoch_timer.ElapsedSeconds();
    train_seconds += epoch_seconds;
    frames_trained += done;
    steps_trained += steps;
    model.Save(options.out_dir, training_run);
    trainer.SaveCheckpoint(checkpoint_path, epoch + 1, training_run);
    log += fmt::format(
        "{},{},{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6g},{:.3f},{:.1f}\n",
        epoch + 1, steps, done, sum.total / steps, sum.classification / steps, sum.box / steps,
        sum.direction / steps, sum.part_warp / steps, sum.segmentation / steps, sum.centre / steps,
        lr, done / epoch_seconds, epoch_seconds);
    WriteFileAtomically(log_path, log);
    write_manifest(epoch + 1);
    summary.epochs_done = epoch + 1;
    ++summary.epochs_run;
    summary.final_loss = sum.total / steps;
  }
  summary.frames_per_second = train_seconds > 0 ? frames_trained / train_seconds : 0;
  summary.seconds_per_step = steps_trained > 0 ? train_seconds / steps_trained : 0;
  summary.seconds = total_timer.ElapsedSeconds();
  return summary;
}

}  // namespace stereodet
