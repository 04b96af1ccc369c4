// ModelHandle's members (model_handle.h), for the family's .cc to instantiate once its Impl is
// complete: `template class ModelHandle<SsdModel, SsdConfig, internal::SsdModelImpl>;`. Includes
// LibTorch.
//
// What a family's Impl provides (the SSD's in ssd_model.cc is an example):
//   Impl(const Config&, ComputeDevice);  builds the network on the device
//   Config config;                       the settings
//   net                                  the network, a torch::nn::ModuleHolder
//   static Config ConfigFromJson(text, source);  the family's *ConfigFromJson
//   void ReadModelJson(text, source);    what else model.json records (stereo settings)
//   int InputChannels() const;           the network input's channels (WeightsRecord)
//   std::string ModelJson(const WeightsRecord&) const;  model.json's text
#ifndef STEREODET_MODELS_MODEL_HANDLE_INTERNAL_H_
#define STEREODET_MODELS_MODEL_HANDLE_INTERNAL_H_

#include <memory>
#include <string>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/model_handle.h"
#include "stereodet/models/model_json.h"

namespace stereodet {

template <typename Model, typename Config, typename Impl>
ModelHandle<Model, Config, Impl>::ModelHandle(const Config& config, uint64_t seed,
                                              ComputeDevice device)
    : impl_(internal::HandleOwned(internal::NewModelImpl<Impl>(config, seed, device))) {}

template <typename Model, typename Config, typename Impl>
Model ModelHandle<Model, Config, Impl>::Load(const std::filesystem::path& model_dir,
                                             ComputeDevice device) {
  return Model(internal::HandleOwned(internal::LoadModelImpl<Impl>(
      model_dir, device, Impl::ConfigFromJson,
      [](Impl& impl, const std::string& text, const std::string& source) {
        impl.ReadModelJson(text, source);
      })));
}

template <typename Model, typename Config, typename Impl>
void ModelHandle<Model, Config, Impl>::Save(const std::filesystem::path& model_dir,
                                            const std::string& training_run) const {
  internal::SaveModelFolder(model_dir, *impl_->net, [&](const std::string& hash) {
    return impl_->ModelJson({.fnv1a64 = hash,
                             .input_channels = impl_->InputChannels(),
                             .parameters = ParameterCount(),
                             .training_run = training_run});
  });
}

template <typename Model, typename Config, typename Impl>
const Config& ModelHandle<Model, Config, Impl>::config() const {
  return impl_->config;
}

template <typename Model, typename Config, typename Impl>
int64_t ModelHandle<Model, Config, Impl>::ParameterCount() const {
  return internal::CountParameters(*impl_->net);
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_MODEL_HANDLE_INTERNAL_H_
