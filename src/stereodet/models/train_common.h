// What every `train` command shares besides its loop (trainer.h): the learning-rate schedule,
// the model folder's rules (never train over a model silently; --resume, --force), and the CSV
// training log kept across a resume.
#ifndef STEREODET_MODELS_TRAIN_COMMON_H_
#define STEREODET_MODELS_TRAIN_COMMON_H_

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/util/check.h"

namespace stereodet {

// Learning rate at `step` of `total_steps` (0-based): a linear warm-up from peak / warmup_steps to
// `peak` over warmup_steps steps, multiplied by a cosine from 1 to final_fraction over all steps.
double WarmupCosineLearningRate(double peak, int warmup_steps, double final_fraction, int64_t step,
                                int64_t total_steps);

// The one-line warning (newline included) for a training of `total_steps` steps that ends before
// its learning-rate warm-up of `warmup_steps` does, so the peak rate is never reached: "warning:
// this training has 12 steps (2 epochs of 6), fewer than the learning-rate warm-up's 100; it never
// reaches the peak rate (more --epochs, more frames or a smaller --batch-size)". Empty when
// total_steps >= warmup_steps.
std::string WarmupWarning(int warmup_steps, int64_t steps_per_epoch, int epochs);

// The checks every training's options share, on the fields of these names (TrainSsdOptions,
// TrainDet3dOptions, TrainRpnOptions::Check call it before their own): --data and --out given,
// epochs and batch size >= 1, a finite learning rate > 0, warm-up steps >= 0, the final rate's
// fraction in [0, 1], threads, max frames and max epochs this run >= 0, a known device, not both
// --resume and --force, the training group's options (distributed.h) and a batch size that its
// ranks divide. Throws stereodet::Error naming the field.
template <typename TrainOptions>
void CheckTrainingSchedule(const TrainOptions& o) {
  STEREODET_CHECK(!o.data_root.empty()) << "--data is required";
  STEREODET_CHECK(!o.out_dir.empty()) << "--out is required";
  STEREODET_CHECK(o.epochs >= 1) << "epochs must be >= 1, got " << o.epochs;
  STEREODET_CHECK(o.batch_size >= 1) << "batch size must be >= 1, got " << o.batch_size;
  STEREODET_CHECK(o.learning_rate > 0.0 && std::isfinite(o.learning_rate))
      << "learning rate must be > 0, got " << o.learning_rate;
  // LibTorch keeps it as a float: past that its own overflow message would be the user's.
  STEREODET_CHECK(o.learning_rate <= std::numeric_limits<float>::max())
      << "learning rate " << o.learning_rate << " is more than a float holds ("
      << std::numeric_limits<float>::max() << ")";
  STEREODET_CHECK(o.warmup_steps >= 0) << "warmup_steps must be >= 0, got " << o.warmup_steps;
  STEREODET_CHECK(o.final_lr_fraction >= 0.0 && o.final_lr_fraction <= 1.0)
      << "final_lr_fraction must be in [0, 1], got " << o.final_lr_fraction;
  STEREODET_CHECK(o.threads >= 0) << "threads must be >= 0, got " << o.threads;
  STEREODET_CHECK(o.max_frames >= 0) << "max_frames must be >= 0, got " << o.max_frames;
  STEREODET_CHECK(o.max_epochs_this_run >= 0)
      << "max_epochs_this_run must be >= 0, got " << o.max_epochs_this_run;
  STEREODET_CHECK(ParseComputeDevice(o.device).has_value())
      << "unknown device '" << o.device << "' (expected cpu or cuda)";
  STEREODET_CHECK(!(o.resume && o.force)) << "--resume and --force exclude each other";
  o.distributed.Check();
  STEREODET_CHECK(o.batch_size % o.distributed.world_size == 0)
      << "--batch-size " << o.batch_size << " must be a multiple of --world-size "
      << o.distributed.world_size << " (each rank trains on batch-size / world-size frames)";
}

// A new training run's id: 16 hex digits that no other run draws (the random device, the clock).
// model.json's "weights" and checkpoint.pt record it, so --resume refuses a foreign checkpoint.
std::string NewTrainingRunId();

// The files a model folder holds for a training (model.pt, model.json, checkpoint.pt,
// train_log.csv, run.json).
inline constexpr char kCheckpointFile[] = "checkpoint.pt";
inline constexpr char kTrainLogFile[] = "train_log.csv";

// Decides how a training uses its model folder, before any work. Returns true when it resumes
// (resume set and a checkpoint present). Throws std::runtime_error when the folder is not empty
// and not a model folder that `tool` ("train ssd") made (CheckOutputFolderOwner: a detection
// folder, a data set, another family's model), or cannot be written; std::invalid_argument when
// it holds a trained model (model.pt or checkpoint.pt) and neither resume (with a checkpoint) nor
// force is set. With force, the earlier model's files are removed. Leftover temporaries of killed
// runs are removed. The caller holds the folder's OutputLock.
bool PrepareModelFolder(const std::filesystem::path& out_dir, const std::string& tool, bool resume,
                        bool force);

// The one-line warning (newline included) for detecting with a model whose training stopped before
// its last epoch, as its run.json records it ("warning: models/x was trained for 3 of its 10
// epochs (its training stopped early; --resume finishes it); its detections are those of an
// unfinished model"). Empty when the training finished, or when the folder has no run.json
// (a model from before run.json existed) or one without both counts.
std::string UnfinishedTrainingWarning(const std::filesystem::path& model_dir);

// The CSV log's text to continue with: `header`, then the lines of `path` (if it exists) whose
// first field (the epoch) is <= epochs_done; a resumed run drops what came after its checkpoint.
std::string KeptLogLines(const std::filesystem::path& path, const std::string& header,
                         int epochs_done);

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAIN_COMMON_H_
