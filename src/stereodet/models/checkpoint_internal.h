// Training checkpoints shared by the detector families: a module's weights, its optimizer's state
// and the epochs done, in one LibTorch archive written atomically. Includes LibTorch.
#ifndef STEREODET_MODELS_CHECKPOINT_INTERNAL_H_
#define STEREODET_MODELS_CHECKPOINT_INTERNAL_H_

#include <torch/torch.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace stereodet::internal {

// What ties a checkpoint to its model folder (the SSD's and det3d's): the model's config as
// model.json writes it (every tensor's shape follows from it), its parameter count and the id of
// the training run that wrote it, which model.json's "weights" object records too.
struct CheckpointRecord {
  std::string config_json;
  int64_t parameters = 0;
  std::string training_run;  // 16 hex digits (NewTrainingRunId); empty = not recorded
};

// The first top-level key whose value differs between two config JSON texts, worded
// "encoding: \"rgbh-fixed\" here, \"rgb\" in the model"; "" when none does.
std::string FirstConfigDifference(const std::string& recorded_text, const std::string& model_text);

void SaveTrainingCheckpoint(const std::filesystem::path& path, const torch::nn::Module& module,
                            const torch::optim::Optimizer& optimizer, int epochs_done,
                            const CheckpointRecord& record);
// Restores what SaveTrainingCheckpoint wrote onto `device`; returns epochs_done. Before loading
// any tensor it checks the checkpoint's record against `expected`: its config and parameter count
// (a checkpoint written before they were recorded is not checked), and, when
// expected.training_run is not empty, its training run. Throws std::runtime_error naming the file
// and the difference ("... was written for another model: encoding: ...", "... is from another
// training run (A) than the folder's model.json (B)"), or when it is missing or does not fit.
int LoadTrainingCheckpoint(const std::filesystem::path& path, torch::nn::Module& module,
                           torch::optim::Optimizer& optimizer, const torch::Device& device,
                           const CheckpointRecord& expected);

// The bytes of a LibTorch archive, a function of its contents alone (the archive's root folder is
// always "archive", whatever file they go to).
std::string SerializeArchive(torch::serialize::OutputArchive& archive);
// Saves `module` to a LibTorch archive at `path` atomically (creating its folder); returns the
// FNV-1a 64 hash (16 hex digits) of the file written: the same weights give the same file and
// hash in any process.
std::string SaveWeights(const std::filesystem::path& path, const torch::nn::Module& module);
// Loads weights into `module` on `device`; throws std::runtime_error naming both files.
void LoadWeights(const std::filesystem::path& path, const std::string& config_source,
                 torch::nn::Module& module, const torch::Device& device = torch::kCPU);

// Checks, before loading, that `weights_path` exists and, when model.json (`config_source`) records
// a hash (`recorded_fnv1a64` not empty), that the file has it: another training's model.pt of the
// same shapes would load and detect garbage. A model.json written before hashes were recorded is
// loaded unchecked. Throws std::runtime_error naming both files.
void CheckWeightsFile(const std::filesystem::path& weights_path, const std::string& config_source,
                      const std::string& recorded_fnv1a64);
// Checks a loaded model's parameter count against model.json's record (none when `recorded` < 0).
void CheckParameterCount(int64_t count, int64_t recorded, const std::filesystem::path& weights_path,
                         const std::string& config_source);

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_CHECKPOINT_INTERNAL_H_
