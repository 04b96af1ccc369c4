// TrainerHandle's members (trainer_handle.h), for the family's .cc to instantiate once its Impl is
// complete: `template class TrainerHandle<internal::SsdTrainerImpl>;`. A family's trainer Impl is a
// TrainerCore (below) plus its losses. Includes LibTorch.
#ifndef STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_
#define STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_

#include <torch/torch.h>

#include <memory>
#include <string>
#include <utility>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/distributed_internal.h"
#include "stereodet/models/trainer_handle.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace internal {

// What every family's trainer holds besides its losses: the AdamW optimizer over the model's
// network, the training group and its gradient reducer, and what ties a checkpoint to the model.
struct TrainerCore {
  // `network` (on `device`) must outlive the trainer; `config_json` is the model's config as
  // model.json writes it (CheckpointRecord).
  TrainerCore(torch::nn::Module& network, torch::Device device, std::string config_json,
              double weight_decay)
      : network(network),
        device(device),
        config_json(std::move(config_json)),
        optimizer(network.parameters(),
                  torch::optim::AdamWOptions(1e-3).weight_decay(weight_decay)) {}

  // Every parameter group's rate from now on. Throws std::invalid_argument when negative.
  void SetLearningRate(double learning_rate) {
    STEREODET_CHECK(learning_rate >= 0.0) << "learning rate must be >= 0, got " << learning_rate;
    for (auto& group : optimizer.param_groups()) {
      static_cast<torch::optim::AdamWOptions&>(group.options()).lr(learning_rate);
    }
  }

  CheckpointRecord Record(const std::string& training_run) const {
    return {.config_json = config_json,
            .parameters = CountParameters(network),
            .training_run = training_run};
  }

  torch::nn::Module& network;
  torch::Device device;
  std::string config_json;
  torch::optim::AdamW optimizer;
  TrainingGroup* group = nullptr;
  std::unique_ptr<GradientReducer> reducer;  // with a group
};

}  // namespace internal

template <typename Impl>
void TrainerHandle<Impl>::SetGroup(TrainingGroup* group) {
  impl_->group = group;
  impl_->reducer.reset();  // its hooks off before the network changes hands
  impl_->reducer = internal::JoinGroup(group, impl_->network);
}

template <typename Impl>
void TrainerHandle<Impl>::SaveCheckpoint(const std::filesystem::path& path, int epochs_done,
                                         const std::string& training_run) const {
  internal::SaveTrainingCheckpoint(path, impl_->network, impl_->optimizer, epochs_done,
                                   impl_->Record(training_run));
}

template <typename Impl>
int TrainerHandle<Impl>::LoadCheckpoint(const std::filesystem::path& path,
                                        const std::string& training_run) {
  return internal::LoadTrainingCheckpoint(path, impl_->network, impl_->optimizer, impl_->device,
                                          impl_->Record(training_run));
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_
