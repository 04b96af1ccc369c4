// Training checkpoints shared by the detector families: a module's weights, its optimizer's state
// and the epochs done, in one LibTorch archive written atomically. Includes LibTorch.
#ifndef STEREODET_MODELS_CHECKPOINT_INTERNAL_H_
#define STEREODET_MODELS_CHECKPOINT_INTERNAL_H_

#include <torch/torch.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "stereodet/models/device_internal.h"
#include "stereodet/models/model_json.h"
#include "stereodet/util/atomic_file.h"

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
// The number of scalars in `module`'s parameters (recursively): what model.json's WeightsRecord
// and each family's ParameterCount() give.
int64_t CountParameters(const torch::nn::Module& module);

// Writes `module`'s weights to `model_dir`/model.pt, then `config_json(hash)` (the family's
// model.json text holding the FNV-1a 64 hash of model.pt, 16 hex digits) to `model_dir`/model.json,
// each atomically; creates the folder. The same weights give the same bytes and hash in any
// process. model.json is written second: until it is in place it still names the previous weights,
// and LoadModelWeights refuses the pair rather than mixing them.
void SaveModelFolder(const std::filesystem::path& model_dir, const torch::nn::Module& module,
                     const std::function<std::string(const std::string& fnv1a64)>& config_json);

// Loads `model_dir`/model.pt into `module` on `device`, reading the file once. Checks it against
// model.json's WeightsRecord in `config_text` (a model.json written before hashes or counts were
// recorded is loaded unchecked on those): its hash (another training's model.pt of the same
// shapes would load and detect garbage), then the parameter count; and refuses non-finite weights
// (a diverged training or an edited file), naming the first tensor. Throws std::runtime_error
// naming model.pt and model.json.
void LoadModelWeights(const std::filesystem::path& model_dir, const std::string& config_text,
                      torch::nn::Module& module, const torch::Device& device);

// `impl` as a ModelHandle or TrainerHandle owns it, with a deleter made here, where Impl is
// complete.
template <typename Impl>
std::unique_ptr<Impl, void (*)(Impl*)> HandleOwned(std::unique_ptr<Impl> impl) {
  return {impl.release(), [](Impl* p) { delete p; }};
}

// A family's model pimpl, new: `config` checked, then the weights drawn from `seed` (the same seed
// gives the same weights). Impl(config, device) builds the network on `device`.
template <typename Impl, typename Config>
std::unique_ptr<Impl> NewModelImpl(const Config& config, uint64_t seed, ComputeDevice device) {
  config.Check();
  torch::manual_seed(seed);
  return std::make_unique<Impl>(config, device);
}

// A family's model pimpl from `model_dir`: model.json's text parsed by `parse_config` (the
// family's *ConfigFromJson(text, source)), Impl(config, device) built, `with_text(impl, text,
// source)` called for what else model.json records (stereo settings), then model.pt loaded into
// impl.net (LoadModelWeights). Throws what those throw, naming the files.
template <typename Impl, typename ParseConfig, typename WithText>
std::unique_ptr<Impl> LoadModelImpl(const std::filesystem::path& model_dir, ComputeDevice device,
                                    ParseConfig parse_config, WithText with_text) {
  const std::filesystem::path config_path = model_dir / kModelConfigFile;
  const std::string text = ReadFile(config_path);
  auto impl = std::make_unique<Impl>(parse_config(text, config_path.string()), device);
  with_text(*impl, text, config_path.string());
  LoadModelWeights(model_dir, text, *impl->net, TorchDevice(device));
  return impl;
}

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_CHECKPOINT_INTERNAL_H_
