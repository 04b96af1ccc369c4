// SsdModel and SsdTrainer: the pimpl boundary between the torch-free API (ssd.h) and LibTorch.
#include "stereodet/models/ssd/ssd_model.h"

#include <cstdint>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/device_internal.h"
#include "stereodet/models/distributed_internal.h"
#include "stereodet/models/model_handle_internal.h"
#include "stereodet/models/model_json_internal.h"
#include "stereodet/models/ssd/ssd_net.h"
#include "stereodet/models/trainer_handle_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

// --- SsdModel
// ---------------------------------------------------------------------------------------

struct internal::SsdModelImpl {
  SsdModelImpl(const SsdConfig& c, ComputeDevice d)
      : config(c),
        device(internal::TorchDevice(d)),
        default_boxes(GenerateDefaultBoxes(c.boxes)),
        net(c) {
    net->to(device);
  }

  SsdConfig config;
  StereoOptions stereo;
  torch::Device device;
  std::vector<DefaultBox> default_boxes;
  // LibTorch's forward() is not const; inference does not change the weights.
  mutable internal::SsdNet net;

  // What ModelHandle asks of a family (model_handle_internal.h).
  static SsdConfig ConfigFromJson(const std::string& text, const std::string& source) {
    return SsdConfigFromJson(text, source);
  }
  void ReadModelJson(const std::string& text, const std::string& source) {
    stereo = ReadStereoRecord(text, source);
  }
  int InputChannels() const { return NetworkInputChannels(config.encoding); }
  std::string ModelJson(const WeightsRecord& weights) const {
    return SsdConfigToJson(config, weights,
                           UsesHeight(config.encoding) ? std::optional(stereo) : std::nullopt);
  }

  torch::Tensor ToTensor(const std::vector<PlanarImage>& inputs) const {
    const int c = NetworkInputChannels(config.encoding);
    std::vector<float> planar = StackPlanar(inputs, c, config.InputHeight(), config.InputWidth());
    return torch::from_blob(
               planar.data(),
               {static_cast<int64_t>(inputs.size()), c, config.InputHeight(), config.InputWidth()},
               torch::kFloat32)
        .clone()
        .to(device);
  }
};

template class ModelHandle<SsdModel, SsdConfig, internal::SsdModelImpl>;

const StereoOptions& SsdModel::stereo() const { return impl_->stereo; }
void SsdModel::set_stereo(const StereoOptions& stereo) {
  stereo.Check();
  impl_->stereo = stereo;
}
const std::vector<DefaultBox>& SsdModel::default_boxes() const { return impl_->default_boxes; }

SsdOutputs SsdModel::Forward(const std::vector<PlanarImage>& inputs) const {
  SsdOutputs outputs;
  outputs.num_images = static_cast<int>(inputs.size());
  outputs.num_boxes = static_cast<int>(impl_->default_boxes.size());
  outputs.num_classes = impl_->config.NumClassesWithBackground();
  if (inputs.empty()) return outputs;
  torch::NoGradGuard no_grad;
  impl_->net->eval();
  auto [deltas, logits] = impl_->net->forward(impl_->ToTensor(inputs));
  STEREODET_CHECK(deltas.size(1) == outputs.num_boxes)
      << "network emits " << deltas.size(1) << " boxes, default boxes are " << outputs.num_boxes;
  internal::CheckFiniteRows(logits, "class scores");
  internal::CheckFiniteRows(deltas, "box offsets");
  const torch::Tensor probabilities = torch::softmax(logits, 2).to(torch::kCPU).contiguous();
  deltas = deltas.to(torch::kCPU).contiguous();
  outputs.deltas.assign(deltas.data_ptr<float>(), deltas.data_ptr<float>() + deltas.numel());
  outputs.probabilities.assign(probabilities.data_ptr<float>(),
                               probabilities.data_ptr<float>() + probabilities.numel());
  return outputs;
}

std::vector<std::vector<ScoredBox>> SsdModel::Detect(const std::vector<PlanarImage>& inputs,
                                                     const DecodeOptions& options) const {
  const SsdOutputs outputs = Forward(inputs);
  std::vector<std::vector<ScoredBox>> detections(inputs.size());
  const size_t boxes = outputs.num_boxes;
  for (size_t i = 0; i < inputs.size(); ++i) {
    detections[i] = DecodeDetections(outputs.deltas.data() + i * boxes * 4,
                                     outputs.probabilities.data() + i * boxes * outputs.num_classes,
                                     outputs.num_classes, impl_->default_boxes, options);
  }
  return detections;
}

int64_t SsdModel::CompressionParameterCount() const {
  return impl_->net->CompressionParameterCount();
}

int64_t SsdModel::MultiplyAccumulates() const {
  return internal::CountMultiplyAccumulates(impl_->config);
}

// --- SsdTrainer
// -------------------------------------------------------------------------------------

void MultiBoxLossOptions::Check() const {
  STEREODET_CHECK(negative_ratio > 0.0) << "negative_ratio must be > 0, got " << negative_ratio;
  STEREODET_CHECK(min_negatives_per_image >= 0)
      << "min_negatives_per_image must be >= 0, got " << min_negatives_per_image;
  STEREODET_CHECK(localization_weight >= 0.0)
      << "localization_weight must be >= 0, got " << localization_weight;
}

void SsdTrainerOptions::Check() const {
  loss.Check();
  STEREODET_CHECK(weight_decay >= 0.0) << "weight_decay must be >= 0, got " << weight_decay;
}

struct internal::SsdTrainerImpl : TrainerCore {
  SsdTrainerImpl(SsdModelImpl& m, const SsdTrainerOptions& o)
      : TrainerCore(*m.net, m.device, SsdConfigToJson(m.config), o.weight_decay),
        model(m),
        options(o) {}

  SsdModelImpl& model;
  SsdTrainerOptions options;

  // Tensors viewing the batch's arrays (no copy; the batch outlives them). With `group`, this
  // rank's share of the group's whole batch's loss.
  internal::MultiBoxLossTerms Loss(const TrainBatch& batch, TrainingGroup* group) const {
    const int64_t boxes = static_cast<int64_t>(model.default_boxes.size());
    STEREODET_CHECK(
        batch.batch_size > 0 && batch.channels == NetworkInputChannels(model.config.encoding) &&
        batch.height == model.config.InputHeight() && batch.width == model.config.InputWidth())
        << "batch of " << batch.batch_size << " x " << batch.channels << " x " << batch.height
        << " x " << batch.width << " does not fit the model";
    STEREODET_CHECK(batch.labels.size() == static_cast<size_t>(batch.batch_size * boxes) &&
                    batch.deltas.size() == static_cast<size_t>(batch.batch_size * boxes * 4) &&
                    batch.images.size() == static_cast<size_t>(batch.batch_size) * batch.channels *
                                               batch.height * batch.width)
        << "batch arrays have the wrong size";
    auto* images = const_cast<float*>(batch.images.data());
    auto* labels = const_cast<int64_t*>(batch.labels.data());
    auto* deltas = const_cast<float*>(batch.deltas.data());
    // On the CPU these stay views; on another device they are copies.
    const torch::Device& device = model.device;
    const torch::Tensor x =
        torch::from_blob(images, {batch.batch_size, batch.channels, batch.height, batch.width},
                         torch::kFloat32)
            .to(device);
    const torch::Tensor target_labels =
        torch::from_blob(labels, {batch.batch_size, boxes}, torch::kInt64).to(device);
    const torch::Tensor target_deltas =
        torch::from_blob(deltas, {batch.batch_size, boxes, 4}, torch::kFloat32).to(device);
    auto [pred_deltas, logits] = model.net->forward(x);
    return internal::MultiBoxLoss(pred_deltas, logits, target_labels, target_deltas, options.loss,
                                  group);
  }

  static LossParts Parts(const internal::MultiBoxLossTerms& terms) {
    return {terms.total.item<double>(), terms.localization.item<double>(),
            terms.confidence.item<double>(), static_cast<int>(terms.num_positive)};
  }
};

template class TrainerHandle<internal::SsdTrainerImpl>;

namespace {

std::unique_ptr<internal::SsdTrainerImpl> NewTrainerImpl(internal::SsdModelImpl& model,
                                                         const SsdTrainerOptions& options) {
  options.Check();
  return std::make_unique<internal::SsdTrainerImpl>(model, options);
}

}  // namespace

SsdTrainer::SsdTrainer(SsdModel& model, const SsdTrainerOptions& options)
    : TrainerHandle(internal::HandleOwned(NewTrainerImpl(*model.impl_, options))) {}

LossParts SsdTrainer::Step(const TrainBatch& batch, double learning_rate) {
  impl_->SetLearningRate(learning_rate);
  impl_->model.net->train();
  impl_->optimizer.zero_grad();
  const internal::MultiBoxLossTerms terms = impl_->Loss(batch, impl_->group);
  internal::Backward(terms.total, impl_->reducer.get());
  impl_->optimizer.step();
  return internal::SsdTrainerImpl::Parts(terms);
}

LossParts SsdTrainer::Evaluate(const TrainBatch& batch) const {
  torch::NoGradGuard no_grad;
  impl_->model.net->eval();
  return internal::SsdTrainerImpl::Parts(impl_->Loss(batch, /*group=*/nullptr));
}

}  // namespace stereodet
