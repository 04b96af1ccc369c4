// What every family's model class is (SsdModel, RpnModel, Det3dModel): a handle on the family's
// network and settings, its `Impl` (defined in the family's .cc, where LibTorch stays: nothing here
// exposes a torch type), with one life cycle written once: a new network from a config and a seed,
// loaded from and saved to a model folder (model_json.h: model.json, model.pt), moved, never
// copied. The members are defined in model_handle_internal.h and instantiated by each family's .cc.
//
// Not thread-safe: one thread at a time may use a model (LibTorch parallelises inside).
#ifndef STEREODET_MODELS_MODEL_HANDLE_H_
#define STEREODET_MODELS_MODEL_HANDLE_H_

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>

#include "stereodet/models/device.h"

namespace stereodet {

// `Model` is the family's class (derived from this one), `Config` its config (model.json's
// settings), `Impl` its network and state.
template <typename Model, typename Config, typename Impl>
class ModelHandle {
 public:
  // A new network, its weights drawn from `seed` (the same seed gives the same weights), on
  // `device` (inputs and outputs stay host arrays). Throws std::invalid_argument for a config
  // that fails its Check().
  ModelHandle(const Config& config, uint64_t seed, ComputeDevice device = ComputeDevice::kCpu);

  // Reads model.json (the config and what else the family records there: the stereo settings of
  // RGB-H and RGB-D models) and model.pt from `model_dir`. Throws std::runtime_error naming the
  // file, and naming both when model.json records other weights than model.pt holds (their hash or
  // parameter count differ).
  static Model Load(const std::filesystem::path& model_dir,
                    ComputeDevice device = ComputeDevice::kCpu);
  // Writes model.pt, then model.json with the weights' hash and `training_run` (WeightsRecord) and
  // what else the family records, into `model_dir` (created if missing), each atomically.
  void Save(const std::filesystem::path& model_dir, const std::string& training_run = {}) const;

  const Config& config() const;
  int64_t ParameterCount() const;  // all trainable parameters

 protected:
  // The deleter is the family's (made where Impl is complete), so a model is destroyed and moved
  // where Impl is not: the family's class declares no destructor or move of its own.
  using ImplPtr = std::unique_ptr<Impl, void (*)(Impl*)>;
  explicit ModelHandle(ImplPtr impl) : impl_(std::move(impl)) {}

  ImplPtr impl_;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_MODEL_HANDLE_H_
