#include "stereodet/models/trainer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "stereodet/models/network_output.h"
#include "stereodet/models/train_common.h"
#include "stereodet/models/train_data.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// A task that records what the loop asks of it; its loss is a function of the step.
class RecordingTask : public TrainingTask {
 public:
  std::vector<std::vector<int>> orders;
  std::vector<std::vector<int>> batches;
  std::vector<int64_t> steps;
  std::vector<double> rates;
  std::vector<int> saves;
  int64_t diverge_at = -1;   // a NaN loss at this step
  int64_t overflow_at = -1;  // a non-finite network output at this step

  // Each epoch's batches, joined: the order the loop visits frames in.
  void BeginEpoch(int /*epoch*/, const std::vector<std::vector<int>>& epoch_batches) override {
    std::vector<int> order;
    for (const std::vector<int>& b : epoch_batches) order.insert(order.end(), b.begin(), b.end());
    orders.push_back(order);
  }
  StepLoss Step(int /*epoch*/, int64_t step, const std::vector<int>& batch,
                double learning_rate) override {
    batches.push_back(batch);
    steps.push_back(step);
    rates.push_back(learning_rate);
    if (step == overflow_at) throw NonFiniteOutputError(1, "box predictions");
    const double loss = step == diverge_at ? std::numeric_limits<double>::quiet_NaN()
                                           : 1.0 / (1.0 + static_cast<double>(step));
    return {loss, {loss / 4, 3 * loss / 4}, {static_cast<int64_t>(batch.size())}};
  }
  void Save(int epochs_done) override { saves.push_back(epochs_done); }
};

TrainingLoopOptions Options(const std::filesystem::path& out, int frames, int epochs) {
  TrainingLoopOptions o;
  o.out_dir = out;
  o.num_frames = frames;
  o.schedule = {.epochs = epochs,
                .batch_size = 3,
                .learning_rate = 0.01,
                .warmup_steps = 2,
                .final_lr_fraction = 0.1,
                .seed = 7,
                .max_epochs_this_run = 0};
  o.columns = {.frames = "frames",
               .terms = {"a_loss", "b_loss"},
               .term_labels = {"a", ""},
               .counts = {"items"},
               .rate = "frames_per_s"};
  o.manifest.tool = "train test";
  o.settings_json = [](int done) { return "{\"epochs_done\": " + std::to_string(done) + "}"; };
  o.progress.stream = nullptr;
  return o;
}

TEST(TrainerTest, EpochsAreTheSeedsPermutationsInBatchesAtTheScheduledRates) {
  TestTempDir dir;
  RecordingTask task;
  const TrainingLoopOptions options = Options(dir.path(), 7, 2);
  const TrainingLoopSummary summary = RunTrainingLoop(task, options);
  EXPECT_EQ(summary.epochs_done, 2);
  EXPECT_EQ(summary.epochs_run, 2);
  EXPECT_EQ(summary.frames_trained, 14);
  EXPECT_EQ(summary.steps_trained, 6);  // ceil(7 / 3) = 3 a epoch
  ASSERT_EQ(task.orders.size(), 2u);
  for (int epoch = 0; epoch < 2; ++epoch) {
    EXPECT_EQ(task.orders[epoch], EpochOrder(7, 7, epoch));
    // The epoch's batches are its order's consecutive slices of 3 (the last one shorter).
    std::vector<int> joined;
    for (int b = 0; b < 3; ++b) {
      const std::vector<int>& batch = task.batches[epoch * 3 + b];
      EXPECT_EQ(batch.size(), b < 2 ? 3u : 1u);
      joined.insert(joined.end(), batch.begin(), batch.end());
    }
    EXPECT_EQ(joined, task.orders[epoch]);
  }
  EXPECT_EQ(task.steps, (std::vector<int64_t>{0, 1, 2, 3, 4, 5}));
  for (int64_t step = 0; step < 6; ++step) {
    EXPECT_DOUBLE_EQ(task.rates[step], WarmupCosineLearningRate(0.01, 2, 0.1, step, 6));
  }
  EXPECT_EQ(task.saves, (std::vector<int>{1, 2}));
  EXPECT_NEAR(summary.final_loss, (1.0 / 4 + 1.0 / 5 + 1.0 / 6) / 3, 1e-12);
  // The log: the header, then one line an epoch with the means of the loss and terms, the sums of
  // the counts and the last step's rate.
  const std::string log = ReadFile(dir.path() / kTrainLogFile);
  EXPECT_THAT(log, ::testing::StartsWith(
                       "epoch,steps,frames,loss,a_loss,b_loss,items,learning_rate,frames_per_s,"
                       "epoch_s\n1,3,7,0.611111,0.152778,0.458333,7,"));
  EXPECT_THAT(ReadFile(dir.path() / "run.json"), HasSubstr("\"epochs_done\": 2"));
}

TEST(TrainerTest, AResumedRunContinuesTheScheduleAndKeepsTheLogUpToItsCheckpoint) {
  TestTempDir dir;
  RecordingTask whole;
  RunTrainingLoop(whole, Options(dir.path() / "whole", 5, 3));
  // Two epochs, then (as after a checkpoint at epoch 1 and a crash) the rest from epoch 1.
  TrainingLoopOptions first = Options(dir.path() / "parts", 5, 3);
  first.schedule.max_epochs_this_run = 2;
  RecordingTask a;
  RunTrainingLoop(a, first);
  TrainingLoopOptions rest = Options(dir.path() / "parts", 5, 3);
  rest.start_epoch = 1;
  RecordingTask b;
  const TrainingLoopSummary summary = RunTrainingLoop(b, rest);
  EXPECT_EQ(summary.epochs_run, 2);
  EXPECT_EQ(b.steps.front(), 2);  // epoch 1's first step: the schedule goes on
  EXPECT_EQ(b.rates, std::vector<double>(whole.rates.begin() + 2, whole.rates.end()));
  EXPECT_EQ(b.orders, std::vector<std::vector<int>>(whole.orders.begin() + 1, whole.orders.end()));
  // The log holds epochs 1, 2, 3 once each (epoch 2 of the first run dropped, written again).
  const std::string log = ReadFile(dir.path() / "parts" / kTrainLogFile);
  int lines = 0;
  std::set<char> epochs;
  for (size_t at = log.find('\n'); at != std::string::npos && at + 1 < log.size();
       at = log.find('\n', at + 1)) {
    epochs.insert(log[at + 1]);
    ++lines;
  }
  EXPECT_EQ(lines, 3);
  EXPECT_EQ(epochs, (std::set<char>{'1', '2', '3'}));
}

TEST(TrainerTest, ANonFiniteLossStopsBeforeTheEpochIsSaved) {
  TestTempDir dir;
  RecordingTask task;
  task.diverge_at = 4;  // epoch 2's second step
  EXPECT_THAT([&] { RunTrainingLoop(task, Options(dir.path(), 7, 2)); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  HasSubstr("training diverged at epoch 2, step 4 (loss nan); try a lower --lr")));
  EXPECT_EQ(task.saves, (std::vector<int>{1}));
  // A network output that overflows inside the step (det3d's part sampling) says the same.
  TestTempDir other;
  RecordingTask overflowing;
  overflowing.overflow_at = 1;
  EXPECT_THAT([&] { RunTrainingLoop(overflowing, Options(other.path(), 7, 2)); },
              ::testing::ThrowsMessage<std::runtime_error>(HasSubstr(
                  "training diverged at epoch 1, step 1 (the network's box predictions for input "
                  "1 of the batch are not finite (NaN or inf)); try a lower --lr")));
  EXPECT_TRUE(overflowing.saves.empty());
}

}  // namespace
}  // namespace stereodet
