// The one training loop of the three families (`train ssd|rpn|det3d`): each family gives its data,
// its loss and its network as a TrainingTask; the loop owns what they share, written once:
//   - the frame order of every epoch (EpochOrder of the run's seed), in batches of batch_size;
//   - the learning rate of every step (WarmupCosineLearningRate over all epochs' steps) and the
//     warning when the warm-up outlasts the training;
//   - the divergence check (a non-finite loss stops the run before anything of that epoch is
//     saved, naming the epoch and step);
//   - a progress line per epoch with the running mean of the loss and its terms;
//   - after every epoch, in this order: the task's Save (model.pt, model.json, checkpoint.pt),
//     the CSV log train_log.csv (kept across a resume: KeptLogLines), run.json's epochs_done.
// Every draw a task makes is a function of (seed, epoch, frame) or (seed, step), never of the
// order or thread, so a resumed training ends with the bytes of an uninterrupted one.
#ifndef STEREODET_MODELS_TRAINER_H_
#define STEREODET_MODELS_TRAINER_H_

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/train_common.h"
#include "stereodet/util/check.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"

namespace stereodet {

// One optimizer step's loss: the total, the family's named terms (averaged over the epoch's steps
// in the log) and counts (summed over the epoch), in TrainingLogColumns' order.
struct StepLoss {
  double total = 0;
  std::vector<double> terms;
  std::vector<int64_t> counts;
};

// The CSV log's columns: epoch, steps, `frames`, loss, terms..., counts..., learning_rate, `rate`,
// epoch_s. Losses are written with 6 decimals, the rate with 6 significant digits, the rate of
// frames with 3 decimals and the epoch's seconds with 1.
struct TrainingLogColumns {
  std::string frames = "frames";  // the column of frames trained ("images" for the SSD)
  std::vector<std::string> terms;
  // The progress line's short name of each term ("box", "cls"); an empty one is not shown.
  std::vector<std::string> term_labels;
  std::vector<std::string> counts;
  std::string rate = "frames_per_s";
  std::string Header() const;  // without the newline
};

// A family's part of a training. The loop calls, per epoch: BeginEpoch, then Step for each batch
// in order, then Save.
class TrainingTask {
 public:
  virtual ~TrainingTask() = default;
  // The frames of every step of the epoch that this process trains on, in step order (indices
  // into the training data: consecutive slices of the epoch's order, or with a training group
  // this rank's part of each, RankSlice), before its first step.
  virtual void BeginEpoch(int epoch, const std::vector<std::vector<int>>& batches) {
    (void)epoch;
    (void)batches;
  }
  // One optimizer step at `learning_rate` on the frames `batch` (the next of BeginEpoch's
  // batches); `step` counts from the training's first step (epoch * steps per epoch + the step in
  // the epoch). Returns the loss before the step; with a training group, this rank's share of the
  // whole batch's loss (terms divided by whole-batch counts, the counts this rank's), which the
  // loop sums over the group.
  virtual StepLoss Step(int epoch, int64_t step, const std::vector<int>& batch,
                        double learning_rate) = 0;
  // Writes the model folder's model.pt and model.json, then checkpoint.pt, after `epochs_done`
  // epochs (a crash in between resumes from the previous epoch and redoes this one).
  virtual void Save(int epochs_done) = 0;
};

// The schedule's fields, as every family's Train*Options names them.
struct TrainingSchedule {
  int epochs = 1;
  int batch_size = 1;
  double learning_rate = 1e-3;
  int warmup_steps = 0;
  double final_lr_fraction = 0;
  uint64_t seed = 1;
  int max_epochs_this_run = 0;  // 0 = run to `epochs`

  template <typename TrainOptions>
  static TrainingSchedule Of(const TrainOptions& o) {
    return {o.epochs, o.batch_size,         o.learning_rate, o.warmup_steps, o.final_lr_fraction,
            o.seed,   o.max_epochs_this_run};
  }
};

struct TrainingLoopOptions {
  std::filesystem::path out_dir;  // the model folder: train_log.csv and run.json go here
  int num_frames = 0;             // the training data's frames (>= 1)
  int start_epoch = 0;            // epochs done before this run (a resumed checkpoint's)
  TrainingSchedule schedule;
  TrainingLogColumns columns;
  // run.json: written before the first epoch and after each, its settings those of
  // settings_json(epochs done so far).
  RunManifest manifest;
  std::function<std::string(int epochs_done)> settings_json;
  ProgressOptions progress;
  // Data-parallel training (distributed.h): each step's batch split over the group's ranks, the
  // steps' losses summed over it; rank 0 alone prints progress and writes the log and run.json.
  // Null: one process.
  TrainingGroup* group = nullptr;

  // What every family fills the same way from its Train*Options `o`: the model folder (out_dir),
  // the schedule, run.json's fixed part (TrainingManifest of `tool`, e.g. "train rpn") and the
  // progress; the family adds its columns, its inputs to the manifest and settings_json.
  template <typename TrainOptions>
  static TrainingLoopOptions Of(const TrainOptions& o, const std::string& tool, int num_frames,
                                int start_epoch);
};

struct TrainingLoopSummary {
  int epochs_done = 0;    // in total, including those before a resume
  int epochs_run = 0;     // in this run
  double final_loss = 0;  // the mean loss of the last epoch run (0 when none ran)
  int64_t frames_trained = 0, steps_trained = 0;  // in this run
  double train_seconds = 0;                       // the epochs' time, without loading
  double FramesPerSecond() const { return train_seconds > 0 ? frames_trained / train_seconds : 0; }
  double SecondsPerStep() const { return steps_trained > 0 ? train_seconds / steps_trained : 0; }
};

// What every family's `train` reports (TrainSsdSummary, TrainRpnSummary and TrainDet3dSummary add
// their own counts).
struct TrainingRunSummary {
  int frames = 0;                // training frames read
  int epochs_done = 0;           // in total, including those before a resume
  int epochs_run = 0;            // in this call
  double final_loss = 0;         // mean training loss of the last epoch run
  double seconds_per_step = 0;   // this call's epochs' time per optimizer step
  double seconds = 0;            // wall time of this call, data preparation included
  double frames_per_second = 0;  // training throughput of this call's epochs (loading excluded)
  int64_t parameters = 0;
  // The epochs, the loss, the time per step and the rate from `done`; `wall_seconds` as
  // `seconds`.
  void Finish(const TrainingLoopSummary& done, double wall_seconds);
};

// Runs the epochs [start_epoch, min(epochs, start_epoch + max_epochs_this_run)) of `task`.
// Throws std::runtime_error when a step's loss is not finite ("training diverged at epoch 3, step
// 412 (loss nan); try a lower --lr"), std::invalid_argument for an empty training set; what the
// task throws goes through.
TrainingLoopSummary RunTrainingLoop(TrainingTask& task, const TrainingLoopOptions& options);

// `progress` for this process of a training: rank 0's (or the only process's) unchanged, the other
// ranks' silent (they would print what rank 0 prints).
ProgressOptions RankProgress(ProgressOptions progress, const TrainingGroup* group);

// The frames a training reads: the split's ids (ImageSets/SPLIT.txt or a split file), the first
// `max_frames` of them when that is > 0. Throws std::invalid_argument for an empty split.
std::vector<std::string> TrainingFrameIds(const KittiDataset& dataset, const std::string& split,
                                          int max_frames);

// run.json's fixed part for a training: its tool ("train ssd"), this build's version, the command
// line and the inputs "data" and "split" (a family adds its own).
RunManifest TrainingManifest(const std::string& tool, const std::string& command_line,
                             const std::filesystem::path& data_root, const std::string& split);

template <typename TrainOptions>
TrainingLoopOptions TrainingLoopOptions::Of(const TrainOptions& o, const std::string& tool,
                                            int num_frames, int start_epoch) {
  TrainingLoopOptions loop;
  loop.out_dir = o.out_dir;
  loop.num_frames = num_frames;
  loop.start_epoch = start_epoch;
  loop.schedule = TrainingSchedule::Of(o);
  loop.manifest = TrainingManifest(tool, o.command_line, o.data_root, o.split);
  loop.progress = o.progress;
  return loop;
}

// A training's model folder, opened before any work: the --out folder is checked against the
// training's inputs (--data's training/ and ImageSets/, and `inputs`, e.g. {"--points", dir}),
// locked for the life of this object (two trainings into one folder would interleave), and
// PrepareModelFolder (train_common.h) decides whether it resumes. When it does, model.json's text
// (the config the training continues with; the flags' config otherwise) and the training run that
// model.json and checkpoint.pt record are read.
// With a training group, rank 0 alone does all that; the other ranks never touch out_dir and
// receive what rank 0 read (whether it resumes, model.json's text, the run's id), and in
// StartEpoch the checkpoint's bytes.
class TrainingFolder {
 public:
  TrainingFolder(const std::filesystem::path& out_dir, const std::filesystem::path& data_root,
                 const std::vector<std::pair<std::string, std::filesystem::path>>& inputs,
                 const std::string& tool, bool resume, bool force, TrainingGroup* group = nullptr);

  bool resuming() const { return resuming_; }
  const std::filesystem::path& config_path() const { return config_path_; }  // out_dir/model.json
  const std::filesystem::path& checkpoint_path() const { return checkpoint_path_; }
  const std::string& config_text() const { return config_text_; }    // when resuming
  const std::string& recorded_run() const { return recorded_run_; }  // when resuming; may be empty
  // The id this run writes into model.json and checkpoint.pt: the recorded one, or a new one
  // (NewTrainingRunId) for a new training and a folder written before ids were recorded.
  const std::string& training_run() const { return training_run_; }

  // The model's config for this run: `requested` for a new training; when resuming, the one
  // model.json records (`parse(text, source)`: the family's *ConfigFromJson), which must have the
  // input `requested` asks for (`input_name(config)`: the --input text, as a std::string). Throws
  // std::invalid_argument naming model.json and both inputs, what `parse` throws.
  template <typename Config, typename Parse, typename InputName>
  Config ModelConfig(const Config& requested, Parse parse, InputName input_name) const {
    if (!resuming_) return requested;
    Config saved = parse(config_text_, config_path_.string());
    STEREODET_CHECK(input_name(saved) == input_name(requested))
        << "--resume: " << config_path_.string() << " was trained with --input "
        << input_name(saved) << ", not " << input_name(requested);
    return saved;
  }

  // The epochs done before this run: 0 for a new training; when resuming, what
  // `load_checkpoint(checkpoint_path(), recorded_run())` returns (the family's trainer loads the
  // weights and optimizer state of checkpoint.pt and returns its epoch count). Throws
  // std::runtime_error naming checkpoint.pt for a negative count, what `load_checkpoint` throws.
  // With a group, rank 0 loads checkpoint.pt and sends its bytes; the other ranks load them from a
  // file of their temporary directory, removed when loaded.
  int StartEpoch(const std::function<int(const std::filesystem::path& checkpoint,
                                         const std::string& recorded_run)>& load_checkpoint) const;

 private:
  std::optional<OutputLock> lock_;  // rank 0's (or the only process's)
  TrainingGroup* group_ = nullptr;
  bool resuming_ = false;
  std::filesystem::path config_path_, checkpoint_path_;
  std::string config_text_, recorded_run_, training_run_;
};

// The settings of run.json every training records, in this order, without braces: "epochs",
// "epochs_done", "batch_size", "learning_rate", "warmup_steps", "final_lr_fraction", "seed",
// "max_frames", "frames" (`frames`: the split's frames read).
std::string ScheduleSettingsJson(const TrainingSchedule& schedule, int max_frames, int epochs_done,
                                 size_t frames);

// What every family's training (TrainSsd, TrainRpn, TrainDet3d) does the same way around its own
// model, data and task, in the order of these calls:
//   TrainingRun<TrainRpnOptions> run(options, "train rpn", {{"--init-from", dir}});
//   RpnConfig config = run.folder().ModelConfig(...);  // the flags', or model.json's
//   RpnModel model(config, run.options().seed, run.device());
//   RpnTrainer trainer(model, ...);
//   if (!run.Resume(trainer, summary)) return summary;  // nothing left to train
//   ... the family's data ...
//   TrainingLoopOptions loop = run.LoopOptions(frames);  // + columns, inputs, settings
//   run.Train(task, loop, summary);
// `TrainOptions` has a Check() and the fields CheckTrainingSchedule names.
template <typename TrainOptions>
class TrainingRun {
  Timer timer_;  // made first: the summary's seconds count everything the run does

 public:
  // Checks `options`, sets LibTorch's threads, resolves the device, joins the training group
  // (distributed.h; null alone) and opens the model folder: TrainingFolder of `tool` ("train
  // rpn") with the family's input flags `inputs` ({"--points", dir}), resuming or not. Throws what
  // those throw, naming the flag or the file.
  TrainingRun(const TrainOptions& options, const std::string& tool,
              const std::vector<std::pair<std::string, std::filesystem::path>>& inputs)
      : options_(CheckedWithThreadsSet(options)),
        device_(ResolveComputeDevice(options_.device)),
        group_(TrainingGroup::Connect(options_.distributed)),
        folder_(options_.out_dir, options_.data_root, inputs, tool, options_.resume, options_.force,
                group_.get()),
        tool_(tool) {
    options_.progress = RankProgress(options_.progress, group_.get());
  }

  // The options, with this rank's progress (RankProgress). A family may complete its own settings
  // in them (the SSD's match scale), not the schedule's.
  const TrainOptions& options() const { return options_; }
  TrainOptions& options() { return options_; }
  ComputeDevice device() const { return device_; }
  TrainingGroup* group() const { return group_.get(); }
  const TrainingFolder& folder() const { return folder_; }

  // Starts `trainer` (the family's: SsdTrainer, RpnTrainer, Det3dTrainer) at this run's first
  // epoch: 0 for a new training; resuming, the epochs of checkpoint.pt, which
  // trainer.LoadCheckpoint(checkpoint, recorded run) loads (TrainingFolder::StartEpoch). Then the
  // trainer trains as one rank of the group (SetGroup). Sets summary.epochs_done. Returns false
  // when no epoch is left to train (summary.seconds set: the training is done already).
  template <typename Trainer>
  bool Resume(Trainer& trainer, TrainingRunSummary& summary) {
    start_epoch_ = folder_.StartEpoch(
        [&](const std::filesystem::path& checkpoint, const std::string& recorded_run) {
          return trainer.LoadCheckpoint(checkpoint, recorded_run);
        });
    trainer.SetGroup(group_.get());
    summary.epochs_done = start_epoch_;
    if (start_epoch_ < options_.epochs) return true;
    summary.seconds = timer_.ElapsedSeconds();
    return false;
  }

  // The loop's options for `num_frames` training frames (TrainingLoopOptions::Of, from the epoch
  // Resume found, in the group); the family adds its columns, inputs and settings_json.
  TrainingLoopOptions LoopOptions(int num_frames) const {
    TrainingLoopOptions loop = TrainingLoopOptions::Of(options_, tool_, num_frames, start_epoch_);
    loop.group = group_.get();
    return loop;
  }

  // run.json's settings every family records (ScheduleSettingsJson), for `frames` frames read.
  std::string ScheduleSettings(int epochs_done, size_t frames) const {
    return ScheduleSettingsJson(TrainingSchedule::Of(options_), options_.max_frames, epochs_done,
                                frames);
  }

  // Runs the epochs (RunTrainingLoop) and completes `summary` (TrainingRunSummary::Finish, with
  // the whole run's seconds).
  void Train(TrainingTask& task, const TrainingLoopOptions& loop, TrainingRunSummary& summary) {
    const TrainingLoopSummary done = RunTrainingLoop(task, loop);
    summary.Finish(done, timer_.ElapsedSeconds());
  }

 private:
  // `options` after its Check() and SetTorchThreads(options.threads), in this order.
  static TrainOptions CheckedWithThreadsSet(const TrainOptions& options) {
    options.Check();
    SetTorchThreads(options.threads);
    return options;
  }

  TrainOptions options_;
  ComputeDevice device_;
  std::unique_ptr<TrainingGroup> group_;
  TrainingFolder folder_;
  std::string tool_;
  int start_epoch_ = 0;
};

// A family's TrainingTask over its model and trainer (SsdModel and SsdTrainer, ...) in `run`'s
// model folder: Save writes the model (model.pt, model.json with the training run), then the
// trainer's checkpoint.pt, as TrainingTask::Save asks. The family adds Step (and BeginEpoch).
// `run`, `model` and `trainer` must outlive the task.
template <typename Model, typename Trainer, typename TrainOptions>
class ModelTrainingTask : public TrainingTask {
 public:
  ModelTrainingTask(const TrainingRun<TrainOptions>& run, const Model& model, Trainer& trainer)
      : options_(run.options()),
        training_run_(run.folder().training_run()),
        model_(model),
        trainer_(trainer) {}

  void Save(int epochs_done) override {
    model_.Save(options_.out_dir, training_run_);
    trainer_.SaveCheckpoint(options_.out_dir / kCheckpointFile, epochs_done, training_run_);
  }

 protected:
  const TrainOptions& options_;
  const std::string& training_run_;
  const Model& model_;
  Trainer& trainer_;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAINER_H_
