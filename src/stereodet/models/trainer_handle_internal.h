// TrainerHandle's members (trainer_handle.h), for the family's .cc to instantiate once its Impl is
// complete: `template class TrainerHandle<internal::SsdTrainerImpl>;`. Includes LibTorch.
//
// What a family's trainer Impl provides:
//   torch::optim::AdamW optimizer;                        over the network's parameters
//   TrainingGroup* group;                                 null alone
//   std::unique_ptr<internal::GradientReducer> reducer;   with a group
//   torch::nn::Module& Network() const;                   the model's network
//   torch::Device Device() const;                         where it lives
//   internal::CheckpointRecord Record(const std::string& training_run) const;  // config, count
#ifndef STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_
#define STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_

#include <string>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/distributed_internal.h"
#include "stereodet/models/trainer_handle.h"

namespace stereodet {

template <typename Impl>
void TrainerHandle<Impl>::SetGroup(TrainingGroup* group) {
  impl_->group = group;
  impl_->reducer.reset();  // its hooks off before the network changes hands
  impl_->reducer = internal::JoinGroup(group, impl_->Network());
}

template <typename Impl>
void TrainerHandle<Impl>::SaveCheckpoint(const std::filesystem::path& path, int epochs_done,
                                         const std::string& training_run) const {
  internal::SaveTrainingCheckpoint(path, impl_->Network(), impl_->optimizer, epochs_done,
                                   impl_->Record(training_run));
}

template <typename Impl>
int TrainerHandle<Impl>::LoadCheckpoint(const std::filesystem::path& path,
                                        const std::string& training_run) {
  return internal::LoadTrainingCheckpoint(path, impl_->Network(), impl_->optimizer, impl_->Device(),
                                          impl_->Record(training_run));
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAINER_HANDLE_INTERNAL_H_
