#include "stereodet/models/ssd/ssd_train.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include "stereodet/models/train_common.h"
#include "stereodet/models/trainer.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/check.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

// The SSD's part of the training loop: batches from a BatchLoader thread (the epoch's order,
// prepared ahead), MultiBox loss.
class SsdTrainingTask : public ModelTrainingTask<SsdModel, SsdTrainer, TrainSsdOptions> {
 public:
  SsdTrainingTask(const TrainingRun<TrainSsdOptions>& run, const SsdModel& model,
                  SsdTrainer& trainer, const SsdTrainingData& data)
      : ModelTrainingTask(run, model, trainer), data_(data) {}

  void BeginEpoch(int epoch, const std::vector<std::vector<int>>& batches) override {
    loader_.reset();  // the previous epoch's thread first
    loader_ = std::make_unique<BatchLoader>(data_, batches, options_.seed, epoch,
                                            options_.loader_capacity);
  }

  StepLoss Step(int /*epoch*/, int64_t /*step*/, const std::vector<int>& batch,
                double learning_rate) override {
    // The loader's batches are the loop's.
    const std::optional<TrainBatch> next = loader_->Next();
    STEREODET_CHECK(next && next->batch_size == static_cast<int>(batch.size()))
        << "the batch loader is out of step with the training loop";
    const LossParts loss = trainer_.Step(*next, learning_rate);
    return {loss.total, {loss.localization, loss.confidence}, {}};
  }

 private:
  const SsdTrainingData& data_;
  std::unique_ptr<BatchLoader> loader_;
};

}  // namespace

void TrainSsdOptions::Check() const {
  model.Check();
  data.Check();
  trainer.Check();
  CheckTrainingSchedule(*this);
  STEREODET_CHECK(loader_capacity >= 1) << "loader_capacity must be >= 1, got " << loader_capacity;
}

double DefaultRgbhMatchScale(const SsdConfig& config, int image_width, int image_height) {
  STEREODET_CHECK(image_width > 0 && image_height > 0)
      << "image size must be positive, got " << image_width << "x" << image_height;
  const double across = static_cast<double>(config.InputWidth()) / image_width;
  const double down = static_cast<double>(config.InputHeight()) / image_height;
  auto about_half = [](double ratio) { return ratio >= 0.45 && ratio <= 0.55; };
  return about_half(across) && about_half(down) ? 0.5 : 1.0;
}

double ScheduledLearningRate(const TrainSsdOptions& options, int64_t step, int64_t total_steps) {
  return WarmupCosineLearningRate(options.learning_rate, options.warmup_steps,
                                  options.final_lr_fraction, step, total_steps);
}

namespace {

// `given`, checked, with --stereo DIR's settings: the heights are the folder's, and so are the
// settings model.json records.
TrainSsdOptions WithStereoFolderSettings(const TrainSsdOptions& given) {
  given.Check();
  TrainSsdOptions options = given;
  if (!options.data.stereo_dir.empty() && UsesHeight(options.model.encoding)) {
    options.data.stereo = ReadStereoFolder(options.data.stereo_dir).stereo;
  }
  return options;
}

}  // namespace

TrainSsdSummary TrainSsd(const TrainSsdOptions& given) {
  TrainingRun<TrainSsdOptions> run(WithStereoFolderSettings(given), "train ssd",
                                   {{"--stereo", given.data.stereo_dir}});
  TrainSsdOptions& options = run.options();
  TrainSsdSummary summary;

  namespace fs = std::filesystem;
  const bool resuming = run.folder().resuming();
  const fs::path& config_path = run.folder().config_path();
  // With --resume the model folder's settings win; asking for different ones is a mistake.
  const SsdConfig config = run.folder().ModelConfig(
      options.model, SsdConfigFromJson,
      [](const SsdConfig& c) { return std::string(InputEncodingName(c.encoding)); });
  if (resuming) {
    const SsdConfig& requested = options.model;
    STEREODET_CHECK(config.InputWidth() == requested.InputWidth() &&
                    config.InputHeight() == requested.InputHeight())
        << "--resume: " << config_path.string() << " has input size " << config.InputWidth() << "x"
        << config.InputHeight() << ", not " << requested.InputWidth() << "x"
        << requested.InputHeight();
    if (UsesHeight(config.encoding)) {
      const std::string differ = DifferingStereoSettings(
          ReadStereoRecord(run.folder().config_text(), config_path.string()), options.data.stereo);
      STEREODET_CHECK(differ.empty()) << "--resume: " << config_path.string()
                                      << " was trained with other stereo settings: " << differ;
    }
  }

  const KittiDataset dataset(options.data_root, "training");
  const std::vector<std::string> ids = TrainingFrameIds(dataset, options.split, options.max_frames);
  if (options.auto_match_scale && !resuming && UsesHeight(config.encoding) &&
      options.data.stereo_dir.empty()) {
    // A missing first image is reported by SsdTrainingData with the other missing files.
    const fs::path first_image = dataset.Paths(ids.front()).image_left;
    if (fs::exists(first_image)) {
      const cv::Mat image = ReadColourImage(first_image);
      options.data.stereo.disparity.match_scale =
          DefaultRgbhMatchScale(config, image.cols, image.rows);
      options.data.stereo.Check();
    }
  }

  SsdModel model(config, options.seed, run.device());
  model.set_stereo(options.data.stereo);  // model.json records what the heights were made with
  SsdTrainer trainer(model, options.trainer);
  summary.parameters = model.ParameterCount();
  summary.compression_parameters = model.CompressionParameterCount();
  if (!run.Resume(trainer, summary)) return summary;

  const Timer data_timer;
  const SsdTrainingData data(dataset, ids, config, options.data, options.progress);
  summary.stereo_seconds = data_timer.ElapsedSeconds();
  summary.frames = data.size();

  TrainingLoopOptions loop = run.LoopOptions(data.size());
  loop.columns = {.frames = "images",
                  .terms = {"localization_loss", "confidence_loss"},
                  .term_labels = {"box", "cls"},
                  .counts = {},
                  .rate = "images_per_s"};
  if (!options.data.stereo_dir.empty()) {
    loop.manifest.inputs.emplace_back("stereo", options.data.stereo_dir.string());
  }
  loop.settings_json = [&](int epochs_done) {
    return fmt::format(
        R"({{"encoding": "{}", {}, "width": {}, "height": {}, "base_channels": {}}})",
        InputEncodingName(config.encoding), run.ScheduleSettings(epochs_done, ids.size()),
        config.InputWidth(), config.InputHeight(), config.base_channels);
  };
  SsdTrainingTask task(run, model, trainer, data);
  run.Train(task, loop, summary);
  return summary;
}

}  // namespace stereodet
