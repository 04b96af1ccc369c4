// What every `train` command shares (the SSD's loop, reused by det3d): the learning-rate schedule,
// the model folder's rules (never train over a model silently; --resume, --force), and the CSV
// training log kept across a resume.
#ifndef STEREODET_MODELS_TRAIN_COMMON_H_
#define STEREODET_MODELS_TRAIN_COMMON_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

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

// A new training run's id: 16 hex digits that no other run draws (the random device, the clock).
// model.json's "weights" and checkpoint.pt record it, so --resume refuses a foreign checkpoint.
std::string NewTrainingRunId();

// The files a model folder holds for a training (model.pt, model.json, checkpoint.pt,
// train_log.csv, run.json).
inline constexpr char kCheckpointFile[] = "checkpoint.pt";
inline constexpr char kTrainLogFile[] = "train_log.csv";

// Decides how a training uses its model folder, before any work. Returns true when it resumes
// (resume set and a checkpoint present). Throws std::invalid_argument when the folder holds a
// trained model (model.pt or checkpoint.pt) and neither resume (with a checkpoint) nor force is
// set; std::runtime_error when it cannot be written. With force, the earlier model's files are
// removed. The caller holds the folder's OutputLock.
bool PrepareModelFolder(const std::filesystem::path& out_dir, bool resume, bool force);

// The CSV log's text to continue with: `header`, then the lines of `path` (if it exists) whose
// first field (the epoch) is <= epochs_done; a resumed run drops what came after its checkpoint.
std::string KeptLogLines(const std::filesystem::path& path, const std::string& header,
                         int epochs_done);

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAIN_COMMON_H_
