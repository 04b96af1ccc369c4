// Training checkpoints shared by the detector families: a module's weights, its optimizer's state
// and the epochs done, in one LibTorch archive written atomically. Includes LibTorch.
#ifndef STEREODET_MODELS_CHECKPOINT_INTERNAL_H_
#define STEREODET_MODELS_CHECKPOINT_INTERNAL_H_

#include <torch/torch.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace stereodet::internal {

void SaveTrainingCheckpoint(const std::filesystem::path& path, const torch::nn::Module& module,
                            const torch::optim::Optimizer& optimizer, int epochs_done);
// Restores what SaveTrainingCheckpoint wrote onto `device`; returns epochs_done. Throws
// std::runtime_error naming the file when it is missing or does not fit the module.
int LoadTrainingCheckpoint(const std::filesystem::path& path, torch::nn::Module& module,
                           torch::optim::Optimizer& optimizer,
                           const torch::Device& device = torch::kCPU);

// Saves `module` to a LibTorch archive at `path` atomically; returns the FNV-1a 64 hash (16 hex
// digits) of the file written.
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
