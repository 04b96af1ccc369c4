#include "stereodet/models/ssd_train.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <sstream>
#include <string>

#include "stereodet/models/train_common.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {

namespace {

constexpr char kLogHeader[] =
    "epoch,steps,images,loss,localization_loss,confidence_loss,learning_rate,images_per_s,epoch_s";

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

TrainSsdSummary TrainSsd(const TrainSsdOptions& given) {
  given.Check();
  // With --stereo DIR the heights are the folder's, and so are the settings model.json records.
  TrainSsdOptions options = given;
  if (!options.data.stereo_dir.empty() && UsesHeight(options.model.encoding)) {
    options.data.stereo = ReadStereoFolder(options.data.stereo_dir).stereo;
  }
  const ComputeDevice device = ResolveComputeDevice(options.device);
  const Timer total_timer;
  SetTorchThreads(options.threads);
  TrainSsdSummary summary;

  namespace fs = std::filesystem;
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir,
                                  {{"--data", options.data_root / "training"},
                                   {"--data", options.data_root / "ImageSets"},
                                   {"--stereo", options.data.stereo_dir}});
  const OutputLock lock(options.out_dir);  // two trainings into one folder would interleave
  // With --resume the model folder's settings win; asking for different ones is a mistake.
  SsdConfig config = options.model;
  const fs::path config_path = options.out_dir / "model.json";
  const fs::path checkpoint_path = options.out_dir / kCheckpointFile;
  const bool resuming =
      PrepareModelFolder(options.out_dir, "train ssd", options.resume, options.force);
  // The id that ties model.json to checkpoint.pt: kept by a resumed run, new for a new one (and
  // for a folder written before ids were recorded).
  std::string recorded_run;
  if (resuming) {
    const std::string saved_text = ReadFile(config_path);
    recorded_run = ReadWeightsRecord(saved_text, config_path.string()).training_run;
    const SsdConfig saved = SsdConfigFromJson(saved_text, config_path.string());
    STEREODET_CHECK(saved.encoding == config.encoding)
        << "--resume: " << config_path.string() << " was trained with --input "
        << InputEncodingName(saved.encoding) << ", not " << InputEncodingName(config.encoding);
    STEREODET_CHECK(saved.InputWidth() == config.InputWidth() &&
                    saved.InputHeight() == config.InputHeight())
        << "--resume: " << config_path.string() << " has input size " << saved.InputWidth() << "x"
        << saved.InputHeight() << ", not " << config.InputWidth() << "x" << config.InputHeight();
    if (UsesHeight(saved.encoding)) {
      const std::string differ = DifferingStereoSettings(
          ReadStereoRecord(saved_text, config_path.string()), options.data.stereo);
      STEREODET_CHECK(differ.empty()) << "--resume: " << config_path.string()
                                      << " was trained with other stereo settings: " << differ;
    }
    config = saved;
  }

  const KittiDataset dataset(options.data_root, "training");
  std::vector<std::string> ids = dataset.ReadSplit(options.split);
  if (options.max_frames > 0 && static_cast<int>(ids.size()) > options.max_frames) {
    ids.resize(options.max_frames);
  }
  STEREODET_CHECK(!ids.empty()) << "split '" << options.split << "' has no frames";
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

  SsdModel model(config, options.seed, device);
  model.set_stereo(options.data.stereo);  // model.json records what the heights were made with
  SsdTrainer trainer(model, options.trainer);
  summary.parameters = model.ParameterCount();
  summary.compression_parameters = model.CompressionParameterCount();
  int start_epoch = resuming ? trainer.LoadCheckpoint(checkpoint_path, recorded_run) : 0;
  const std::string training_run = recorded_run.empty() ? NewTrainingRunId() : recorded_run;
  STEREODET_CHECK(start_epoch >= 0) << "bad epoch count in " << checkpoint_path.string();
  summary.epochs_done = start_epoch;
  if (start_epoch >= options.epochs) {
    summary.seconds = total_timer.ElapsedSeconds();
    return summary;
  }

  const Timer data_timer;
  const SsdTrainingData data(dataset, ids, config, options.data, options.progress);
  summary.stereo_seconds = data_timer.ElapsedSeconds();
  summary.frames = data.size();

  RunManifest manifest;
  manifest.tool = "train ssd";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"data", options.data_root.string()}, {"split", options.split}};
  if (!options.data.stereo_dir.empty()) {
    manifest.inputs.emplace_back("stereo", options.data.stereo_dir.string());
  }
  auto write_manifest = [&](int epochs_done) {
    manifest.settings_json = fmt::format(
        R"({{"encoding": "{}", "epochs": {}, "epochs_done": {}, "batch_size": {}, )"
        R"("learning_rate": {}, "warmup_steps": {}, "final_lr_fraction": {}, "seed": {}, )"
        R"("max_frames": {}, "frames": {}, "width": {}, "height": {}, "base_channels": {}}})",
        InputEncodingName(config.encoding), options.epochs, epochs_done, options.batch_size,
        options.learning_rate, options.warmup_steps, options.final_lr_fraction, options.seed,
        options.max_frames, ids.size(), config.InputWidth(), config.InputHeight(),
        config.base_channels);
    WriteRunManifest(options.out_dir, manifest);
  };
  write_manifest(start_epoch);
  const std::filesystem::path log_path = options.out_dir / kTrainLogFile;
  std::string log = KeptLogLines(log_path, kLogHeader, start_epoch);

  const int64_t steps_per_epoch = (data.size() + options.batch_size - 1) / options.batch_size;
  const int64_t total_steps = steps_per_epoch * options.epochs;
  if (const std::string warning =
          WarmupWarning(options.warmup_steps, steps_per_epoch, options.epochs);
      !warning.empty() && options.progress.stream != nullptr) {
    std::fputs(warning.c_str(), options.progress.stream);
  }
  double train_seconds = 0;
  int64_t images_trained = 0;
  const int end_epoch = options.max_epochs_this_run > 0
                            ? std::min(options.epochs, start_epoch + options.max_epochs_this_run)
                            : options.epochs;
  for (int epoch = start_epoch; epoch < end_epoch; ++epoch) {
    const Timer epoch_timer;
    BatchLoader loader(data, EpochOrder(data.size(), options.seed, epoch), options.batch_size,
                       options.seed, epoch, options.loader_capacity);
    ProgressReporter progress(fmt::format("epoch {}/{}", epoch + 1, options.epochs), data.size(),
                              options.progress);
    double loss_sum = 0, loc_sum = 0, conf_sum = 0, lr = 0;
    int64_t step = epoch * steps_per_epoch;
    int steps = 0, images = 0;
    while (std::optional<TrainBatch> batch = loader.Next()) {
      lr = ScheduledLearningRate(options, step, total_steps);
      const LossParts loss = trainer.Step(*batch, lr);
      STEREODET_CHECK_IO(std::isfinite(loss.total))
          << "training diverged at epoch " << epoch + 1 << ", step " << step << " (loss "
          << loss.total << "); try a lower --lr";
      loss_sum += loss.total;
      loc_sum += loss.localization;
      conf_sum += loss.confidence;
      ++steps;
      ++step;
      images += batch->batch_size;
      progress.Add(batch->batch_size,
                   fmt::format("loss {:.3f} (box {:.3f} cls {:.3f})", loss_sum / steps,
                               loc_sum / steps, conf_sum / steps));
    }
    progress.Finish();
    const double epoch_seconds = epoch_timer.ElapsedSeconds();
    train_seconds += epoch_seconds;
    images_trained += images;

    // Weights and config first, then the checkpoint: a crash in between resumes from the previous
    // epoch and redoes this one.
    model.Save(options.out_dir, training_run);
    trainer.SaveCheckpoint(checkpoint_path, epoch + 1, training_run);
    log += fmt::format("{},{},{},{:.6f},{:.6f},{:.6f},{:.6g},{:.3f},{:.1f}\n", epoch + 1, steps,
                       images, loss_sum / steps, loc_sum / steps, conf_sum / steps, lr,
                       images / epoch_seconds, epoch_seconds);
    WriteFileAtomically(log_path, log);
    write_manifest(epoch + 1);
    summary.epochs_done = epoch + 1;
    ++summary.epochs_run;
    summary.final_loss = loss_sum / steps;
  }
  summary.images_per_second = train_seconds > 0 ? images_trained / train_seconds : 0;
  summary.seconds = total_timer.ElapsedSeconds();
  return summary;
}

}  // namespace stereodet
