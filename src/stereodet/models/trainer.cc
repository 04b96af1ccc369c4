#include "stereodet/models/trainer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "stereodet/models/model_json.h"
#include "stereodet/models/network_output.h"
#include "stereodet/models/train_common.h"
#include "stereodet/models/train_data.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

std::string TrainingLogColumns::Header() const {
  std::string header = "epoch,steps," + frames + ",loss";
  for (const std::string& term : terms) header += "," + term;
  for (const std::string& count : counts) header += "," + count;
  return header + ",learning_rate," + rate + ",epoch_s";
}

namespace {

// The running means of an epoch's loss and terms, and its counts' sums.
struct EpochLoss {
  double total = 0;
  std::vector<double> terms;
  std::vector<int64_t> counts;
  int steps = 0;

  void Add(const StepLoss& loss, const TrainingLogColumns& columns) {
    STEREODET_CHECK(loss.terms.size() == columns.terms.size() &&
                    loss.counts.size() == columns.counts.size())
        << "a step gave " << loss.terms.size() << " loss terms and " << loss.counts.size()
        << " counts; the log has " << columns.terms.size() << " and " << columns.counts.size();
    if (terms.empty()) {
      terms.assign(loss.terms.size(), 0.0);
      counts.assign(loss.counts.size(), 0);
    }
    total += loss.total;
    for (size_t i = 0; i < terms.size(); ++i) terms[i] += loss.terms[i];
    for (size_t i = 0; i < counts.size(); ++i) counts[i] += loss.counts[i];
    ++steps;
  }
  double Mean() const { return total / steps; }
  double TermMean(size_t i) const { return terms[i] / steps; }

  std::string ProgressText(const TrainingLogColumns& columns) const {
    std::string text = fmt::format("loss {:.3f}", Mean());
    std::string parts;
    for (size_t i = 0; i < terms.size(); ++i) {
      if (i >= columns.term_labels.size() || columns.term_labels[i].empty()) continue;
      parts +=
          fmt::format("{}{} {:.3f}", parts.empty() ? "" : " ", columns.term_labels[i], TermMean(i));
    }
    return parts.empty() ? text : text + " (" + parts + ")";
  }
};

// The steps of an epoch: consecutive slices of `order` of batch_size frames (the last may be
// smaller), each cut to this rank's part (RankSlice) with a group. Also the whole batches' sizes.
std::vector<std::vector<int>> EpochBatches(const std::vector<int>& order, int batch_size,
                                           const TrainingGroup* group, std::vector<int>& sizes) {
  std::vector<std::vector<int>> batches;
  const int n = static_cast<int>(order.size());
  for (int begin = 0; begin < n; begin += batch_size) {
    const int end = std::min(n, begin + batch_size);
    sizes.push_back(end - begin);
    const BatchSlice slice = group == nullptr
                                 ? BatchSlice{0, end - begin}
                                 : RankSlice(end - begin, group->rank(), group->world_size());
    batches.emplace_back(order.begin() + begin + slice.begin, order.begin() + begin + slice.end);
  }
  return batches;
}

// A rank's share of a step's loss -> the whole batch's, on every rank: the total and the terms
// (each rank's divided by the whole batch's counts) and the counts are sums over the group.
void SumOverGroup(TrainingGroup& group, StepLoss& loss) {
  std::vector<double> values{loss.total};
  values.insert(values.end(), loss.terms.begin(), loss.terms.end());
  for (const int64_t count : loss.counts) values.push_back(static_cast<double>(count));
  group.AllReduceSum(values);
  loss.total = values[0];
  for (size_t i = 0; i < loss.terms.size(); ++i) loss.terms[i] = values[1 + i];
  for (size_t i = 0; i < loss.counts.size(); ++i) {
    loss.counts[i] = static_cast<int64_t>(std::llround(values[1 + loss.terms.size() + i]));
  }
}

}  // namespace

TrainingLoopSummary RunTrainingLoop(TrainingTask& task, const TrainingLoopOptions& options) {
  const TrainingSchedule& schedule = options.schedule;
  const int n = options.num_frames;
  STEREODET_CHECK(n >= 1) << "no frames to train on";
  STEREODET_CHECK(schedule.batch_size >= 1) << "batch size must be >= 1";
  TrainingGroup* const group = options.group;
  const int world_size = group == nullptr ? 1 : group->world_size();
  CheckBatchesSplit(n, schedule.batch_size, world_size);
  if (group != nullptr) {
    // Ranks that disagree on these would train different models, or wait for each other forever.
    group->CheckSame(
        "the schedule",
        fmt::format("{} frames, from epoch {} of {} ({} this run at most, 0 = all), batch size {}, "
                    "learning rate {}, warm-up {}, final fraction {}, seed {}",
                    n, options.start_epoch, schedule.epochs, schedule.max_epochs_this_run,
                    schedule.batch_size, schedule.learning_rate, schedule.warmup_steps,
                    schedule.final_lr_fraction, schedule.seed));
  }
  // Rank 0 owns the folder and the terminal; the others train silently.
  const bool writes = group == nullptr || group->IsRoot();
  const ProgressOptions progress_options = RankProgress(options.progress, group);
  TrainingLoopSummary summary;
  summary.epochs_done = options.start_epoch;

  RunManifest manifest = options.manifest;
  auto write_manifest = [&](int epochs_done) {
    if (!writes) return;
    manifest.settings_json = options.settings_json(epochs_done);
    WriteRunManifest(options.out_dir, manifest);
  };
  write_manifest(options.start_epoch);
  const std::filesystem::path log_path = options.out_dir / kTrainLogFile;
  std::string log =
      writes ? KeptLogLines(log_path, options.columns.Header(), options.start_epoch) : "";

  const int64_t steps_per_epoch = (n + schedule.batch_size - 1) / schedule.batch_size;
  const int64_t total_steps = steps_per_epoch * schedule.epochs;
  if (const std::string warning =
          WarmupWarning(schedule.warmup_steps, steps_per_epoch, schedule.epochs);
      !warning.empty() && progress_options.stream != nullptr) {
    std::fputs(warning.c_str(), progress_options.stream);
  }
  const int end_epoch =
      schedule.max_epochs_this_run > 0
          ? std::min(schedule.epochs, options.start_epoch + schedule.max_epochs_this_run)
          : schedule.epochs;
  for (int epoch = options.start_epoch; epoch < end_epoch; ++epoch) {
    const Timer epoch_timer;
    std::vector<int> sizes;
    const std::vector<std::vector<int>> batches =
        EpochBatches(EpochOrder(n, schedule.seed, epoch), schedule.batch_size, group, sizes);
    task.BeginEpoch(epoch, batches);
    ProgressReporter progress(fmt::format("epoch {}/{}", epoch + 1, schedule.epochs), n,
                              progress_options);
    EpochLoss sum;
    double lr = 0;
    int64_t step = epoch * steps_per_epoch;
    int frames = 0;
    for (size_t b = 0; b < batches.size(); ++b) {
      lr = WarmupCosineLearningRate(schedule.learning_rate, schedule.warmup_steps,
                                    schedule.final_lr_fraction, step, total_steps);
      StepLoss loss;
      try {
        loss = task.Step(epoch, step, batches[b], lr);
      } catch (const NonFiniteOutputError& e) {
        // A network output the step needs finite (det3d's part sampling) overflowed first.
        STEREODET_THROW_IO() << "training diverged at epoch " << epoch + 1 << ", step " << step
                             << " (" << e.what() << "); try a lower --lr";
      }
      if (group != nullptr) SumOverGroup(*group, loss);
      STEREODET_CHECK_IO(std::isfinite(loss.total))
          << "training diverged at epoch " << epoch + 1 << ", step " << step << " (loss "
          << loss.total << "); try a lower --lr";
      sum.Add(loss, options.columns);
      ++step;
      frames += sizes[b];
      progress.Add(sizes[b], sum.ProgressText(options.columns));
    }
    progress.Finish();
    const double epoch_seconds = epoch_timer.ElapsedSeconds();
    summary.train_seconds += epoch_seconds;
    summary.frames_trained += frames;
    summary.steps_trained += sum.steps;

    if (writes) {
      task.Save(epoch + 1);
      log += fmt::format("{},{},{},{:.6f}", epoch + 1, sum.steps, frames, sum.Mean());
      for (size_t i = 0; i < sum.terms.size(); ++i) {
        log += fmt::format(",{:.6f}", sum.TermMean(i));
      }
      for (const int64_t count : sum.counts) log += fmt::format(",{}", count);
      log += fmt::format(",{:.6g},{:.3f},{:.1f}\n", lr, frames / epoch_seconds, epoch_seconds);
      WriteFileAtomically(log_path, log);
      write_manifest(epoch + 1);
    }
    summary.epochs_done = epoch + 1;
    ++summary.epochs_run;
    summary.final_loss = sum.Mean();
  }
  return summary;
}

std::string ScheduleSettingsJson(const TrainingSchedule& schedule, int max_frames, int epochs_done,
                                 size_t frames) {
  return fmt::format(
      R"("epochs": {}, "epochs_done": {}, "batch_size": {}, "learning_rate": {}, )"
      R"("warmup_steps": {}, "final_lr_fraction": {}, "seed": {}, "max_frames": {}, "frames": {})",
      schedule.epochs, epochs_done, schedule.batch_size, schedule.learning_rate,
      schedule.warmup_steps, schedule.final_lr_fraction, schedule.seed, max_frames, frames);
}

ProgressOptions RankProgress(ProgressOptions progress, const TrainingGroup* group) {
  if (group != nullptr && !group->IsRoot()) progress.stream = nullptr;
  return progress;
}

std::vector<std::string> TrainingFrameIds(const KittiDataset& dataset, const std::string& split,
                                          int max_frames) {
  std::vector<std::string> ids = dataset.ReadSplit(split);
  if (max_frames > 0 && static_cast<int>(ids.size()) > max_frames) ids.resize(max_frames);
  STEREODET_CHECK(!ids.empty()) << "split '" << split << "' has no frames";
  return ids;
}

RunManifest TrainingManifest(const std::string& tool, const std::string& command_line,
                             const std::filesystem::path& data_root, const std::string& split) {
  RunManifest manifest;
  manifest.tool = tool;
  manifest.version = StereodetVersion();
  manifest.command_line = command_line;
  manifest.inputs = {{"data", data_root.string()}, {"split", split}};
  return manifest;
}

namespace {

// Runs before the lock is taken: an --out inside an input is refused before anything is created.
const std::filesystem::path& CheckedOutDir(
    const std::filesystem::path& out_dir, const std::filesystem::path& data_root,
    std::vector<std::pair<std::string, std::filesystem::path>> inputs) {
  inputs.insert(inputs.begin(),
                {{"--data", data_root / "training"}, {"--data", data_root / "ImageSets"}});
  CheckOutputDoesNotOverlapInputs("--out", out_dir, inputs);
  return out_dir;
}

}  // namespace

void TrainingRunSummary::Finish(const TrainingLoopSummary& done, double wall_seconds) {
  epochs_done = done.epochs_done;
  epochs_run = done.epochs_run;
  final_loss = done.final_loss;
  seconds_per_step = done.SecondsPerStep();
  frames_per_second = done.FramesPerSecond();
  seconds = wall_seconds;
}

int TrainingFolder::StartEpoch(
    const std::function<int(const std::filesystem::path&, const std::string&)>& load_checkpoint)
    const {
  if (!resuming_) return 0;
  if (group_ == nullptr || group_->IsRoot()) {
    const int epochs = load_checkpoint(checkpoint_path_, recorded_run_);
    STEREODET_CHECK_IO(epochs >= 0)
        << "bad epoch count " << epochs << " in " << checkpoint_path_.string();
    if (group_ != nullptr) {
      // What rank 0 loaded, byte for byte, for ranks that may not see its disk.
      group_->Broadcast(ReadFile(checkpoint_path_));
    }
    return epochs;
  }
  const std::string bytes = group_->Broadcast("");
  namespace fs = std::filesystem;
  const fs::path temporary =
      fs::temp_directory_path() /
      fmt::format("stereodet-checkpoint-{}-rank{}.pt", NewTrainingRunId(), group_->rank());
  struct Remove {
    fs::path path;
    ~Remove() {
      std::error_code ignored;
      fs::remove(path, ignored);
    }
  } remove{temporary};
  WriteFileAtomically(temporary, bytes);
  const int epochs = load_checkpoint(temporary, recorded_run_);
  STEREODET_CHECK_IO(epochs >= 0) << "bad epoch count " << epochs << " in rank 0's "
                                  << checkpoint_path_.string();
  return epochs;
}

TrainingFolder::TrainingFolder(
    const std::filesystem::path& out_dir, const std::filesystem::path& data_root,
    const std::vector<std::pair<std::string, std::filesystem::path>>& inputs,
    const std::string& tool, bool resume, bool force, TrainingGroup* group)
    : group_(group),
      config_path_(out_dir / kModelConfigFile),
      checkpoint_path_(out_dir / kCheckpointFile) {
  if (group_ == nullptr || group_->IsRoot()) {
    lock_.emplace(CheckedOutDir(out_dir, data_root, inputs));
    resuming_ = PrepareModelFolder(out_dir, tool, resume, force);
    if (resuming_) {
      config_text_ = ReadFile(config_path_);
      recorded_run_ = ReadWeightsRecord(config_text_, config_path_.string()).training_run;
    }
    training_run_ = recorded_run_.empty() ? NewTrainingRunId() : recorded_run_;
  }
  if (group_ != nullptr) {
    resuming_ = group_->Broadcast(resuming_ ? "1" : "0") == "1";
    config_text_ = group_->Broadcast(config_text_);
    recorded_run_ = group_->Broadcast(recorded_run_);
    training_run_ = group_->Broadcast(training_run_);
  }
}

}  // namespace stereodet
