// What every family's trainer is (SsdTrainer, RpnTrainer, Det3dTrainer): a handle on the family's
// optimizer state and losses, its `Impl` (defined in the family's .cc with LibTorch), which trains
// the family's model in place. Joining a training group and the checkpoints are written once: the
// members are defined in trainer_handle_internal.h and instantiated by each family's .cc. A
// family's trainer adds its own Step and Evaluate.
//
// Not thread-safe: one thread at a time. The model a trainer was made with must outlive it.
#ifndef STEREODET_MODELS_TRAINER_HANDLE_H_
#define STEREODET_MODELS_TRAINER_HANDLE_H_

#include <filesystem>
#include <memory>
#include <string>
#include <utility>

#include "stereodet/models/distributed.h"

namespace stereodet {

template <typename Impl>
class TrainerHandle {
 public:
  // Trains as one rank of `group` from now on (null: alone): the batch norms synchronized over it,
  // the loss's counts and the gradients summed over it (distributed.h), and the model's weights
  // now those of rank 0. `group` must outlive the trainer or the next call.
  void SetGroup(TrainingGroup* group);

  // Weights + optimizer state + `epochs_done`, the model's config (its model.json settings, hence
  // every tensor's shape), its parameter count and `training_run` (the id that model.json's
  // WeightsRecord holds), written atomically (checkpoint_internal.h).
  void SaveCheckpoint(const std::filesystem::path& path, int epochs_done,
                      const std::string& training_run = {}) const;
  // Restores what SaveCheckpoint wrote (into the trainer's model); returns epochs_done. Throws
  // std::runtime_error naming the file, before loading anything, if it is missing or does not fit
  // the model: its recorded config differs from the model's (the message names the first field
  // that differs, e.g. "encoding"), or its parameter count does, or `training_run` is not empty
  // and the checkpoint records another run or none (a checkpoint of another training, copied in).
  // A checkpoint written before configs were recorded is checked by LibTorch's shapes only.
  int LoadCheckpoint(const std::filesystem::path& path, const std::string& training_run = {});

 protected:
  // As ModelHandle's: the family's deleter, so the family's trainer declares no destructor.
  using ImplPtr = std::unique_ptr<Impl, void (*)(Impl*)>;
  explicit TrainerHandle(ImplPtr impl) : impl_(std::move(impl)) {}

  ImplPtr impl_;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAINER_HANDLE_H_
