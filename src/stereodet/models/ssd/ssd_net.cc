#include "stereodet/models/ssd/ssd_net.h"

#include <algorithm>
#include <cmath>

#include "stereodet/models/distributed_internal.h"
#include "stereodet/util/check.h"

namespace stereodet::internal {

std::vector<ConvSpec> BackboneSpec(int base_channels) {
  const int b = base_channels;
  return {
      {3, b, 2, false},         {b, 2 * b, 2, false},    {2 * b, 2 * b, 1, false},
      {2 * b, 4 * b, 2, false}, {4 * b, 4 * b, 1, true},  // map 1, stride 8
      {4 * b, 8 * b, 2, false}, {8 * b, 8 * b, 1, true},  // map 2, stride 16
      {8 * b, 8 * b, 2, true},                            // map 3, stride 32
      {8 * b, 8 * b, 2, true},                            // map 4, stride 64
  };
}

namespace {

torch::nn::Conv2dOptions Conv3x3(int in, int out, int stride, bool bias) {
  return torch::nn::Conv2dOptions(in, out, 3).stride(stride).padding(1).bias(bias);
}

}  // namespace

SsdNetImpl::SsdNetImpl(const SsdConfig& config)
    : learned_compression_(config.encoding == InputEncoding::kRgbhLearned),
      boxes_per_cell_(config.boxes.BoxesPerCell()),
      num_classes_(config.NumClassesWithBackground()) {
  config.Check();
  if (learned_compression_) {
    // Initialised like a 1x1 Conv2d(3, 2) (Kaiming-uniform bound 1/sqrt(fan_in)).
    compress_ = register_parameter(
        "compress", torch::empty({2, 3}).uniform_(-1.0 / std::sqrt(3.0), 1.0 / std::sqrt(3.0)));
  }
  stages_ = register_module("stages", torch::nn::ModuleList());
  box_heads_ = register_module("box_heads", torch::nn::ModuleList());
  class_heads_ = register_module("class_heads", torch::nn::ModuleList());
  torch::nn::Sequential stage;
  bool first = true;
  for (const ConvSpec& spec : BackboneSpec(config.base_channels)) {
    // No conv bias: batch norm's shift replaces it.
    torch::nn::Conv2d conv(Conv3x3(spec.in_channels, spec.out_channels, spec.stride, false));
    if (first) {
      stem_ = register_module("stem", conv);
      first = false;
    } else {
      stage->push_back(conv);
    }
    stage->push_back(BatchNorm2dSync(spec.out_channels));
    stage->push_back(torch::nn::ReLU(torch::nn::ReLUOptions().inplace(true)));
    if (spec.feature_map) {
      stages_->push_back(stage);
      box_heads_->push_back(
          torch::nn::Conv2d(Conv3x3(spec.out_channels, boxes_per_cell_ * 4, 1, true)));
      class_heads_->push_back(
          torch::nn::Conv2d(Conv3x3(spec.out_channels, boxes_per_cell_ * num_classes_, 1, true)));
      stage = torch::nn::Sequential();
    }
  }
}

torch::Tensor SsdNetImpl::Stem(const torch::Tensor& input) {
  if (!learned_compression_) return stem_->forward(input);
  // The paper's learned compression, 5-bit (R, G, B) -> 2 channels by a 1x1 convolution C, then the
  // stem S on (C rgb, height). Both are linear and C has no bias, so S(C rgb, h) is one 3x3
  // convolution of the 4-channel input with weights S[:, :2] C (per tap) and S[:, 2] for the
  // height: exact, also at the zero-padded border (C 0 = 0), and gradients reach both S and C.
  const torch::Tensor& stem = stem_->weight;  // [b, 3, 3, 3]
  const torch::Tensor colour = torch::einsum("okhw,kc->ochw", {stem.narrow(1, 0, 2), compress_});
  const torch::Tensor folded = torch::cat({colour, stem.narrow(1, 2, 1)}, 1);  // [b, 4, 3, 3]
  return torch::nn::functional::conv2d(
      input, folded, torch::nn::functional::Conv2dFuncOptions().stride(2).padding(1));
}

std::pair<torch::Tensor, torch::Tensor> SsdNetImpl::forward(torch::Tensor input) {
  torch::Tensor x = Stem(input);
  const int64_t n = x.size(0);
  std::vector<torch::Tensor> deltas, logits;
  for (size_t k = 0; k < stages_->size(); ++k) {
    x = stages_[k]->as<torch::nn::Sequential>()->forward(x);
    // [N, A*K, H, W] -> [N, H, W, A*K] -> [N, H*W*A, K]: row, column, box, the default-box order.
    deltas.push_back(box_heads_[k]
                         ->as<torch::nn::Conv2d>()
                         ->forward(x)
                         .permute({0, 2, 3, 1})
                         .reshape({n, -1, 4}));
    logits.push_back(class_heads_[k]
                         ->as<torch::nn::Conv2d>()
                         ->forward(x)
                         .permute({0, 2, 3, 1})
                         .reshape({n, -1, num_classes_}));
  }
  return {torch::cat(deltas, 1), torch::cat(logits, 1)};
}

int64_t SsdNetImpl::CompressionParameterCount() const {
  return learned_compression_ ? compress_.numel() : 0;
}

MultiBoxLossTerms MultiBoxLoss(const torch::Tensor& pred_deltas, const torch::Tensor& logits,
                               const torch::Tensor& labels, const torch::Tensor& target_deltas,
                               const MultiBoxLossOptions& options, TrainingGroup* group) {
  namespace F = torch::nn::functional;
  const int64_t num_classes = logits.size(2);
  const torch::Tensor positive = labels > 0;
  const torch::Tensor valid = labels >= 0;
  const torch::Tensor num_positive = positive.sum(1);  // [N]
  const int64_t total_positive = num_positive.sum().item<int64_t>();
  const double normalizer = std::max(GlobalCount(group, static_cast<double>(total_positive)), 1.0);

  torch::Tensor localization = torch::zeros({}, pred_deltas.options());
  if (total_positive > 0) {
    localization = F::smooth_l1_loss(pred_deltas.index({positive}), target_deltas.index({positive}),
                                     F::SmoothL1LossFuncOptions().reduction(torch::kSum));
  }

  // Per-box cross-entropy; ignored boxes get class 0 here and are masked out below.
  const torch::Tensor per_box =
      F::cross_entropy(logits.reshape({-1, num_classes}), labels.clamp_min(0).reshape({-1}),
                       F::CrossEntropyFuncOptions().reduction(torch::kNone))
          .reshape(labels.sizes());

  torch::Tensor negative;
  {
    torch::NoGradGuard no_grad;
    // Hard negative mining: rank the background boxes by their loss, highest first; positives and
    // ignored boxes rank last (-1 < any cross-entropy).
    const torch::Tensor candidate = valid & ~positive;
    const torch::Tensor mining = per_box.detach().masked_fill(~candidate, -1.0);
    const torch::Tensor order = mining.argsort(1, /*descending=*/true);
    const torch::Tensor rank = order.argsort(/*dim=*/1, /*descending=*/false);
    const torch::Tensor wanted = (num_positive.to(torch::kDouble) * options.negative_ratio)
                                     .floor()
                                     .to(torch::kLong)
                                     .clamp_min(options.min_negatives_per_image);
    const torch::Tensor available = candidate.sum(1);
    const torch::Tensor num_negative = torch::minimum(wanted, available).unsqueeze(1);
    negative = (rank < num_negative) & candidate;
  }
  const torch::Tensor confidence = per_box.masked_select(positive | negative).sum();

  MultiBoxLossTerms terms;
  terms.localization = localization / normalizer;
  terms.confidence = confidence / normalizer;
  terms.total = options.localization_weight * terms.localization + terms.confidence;
  terms.num_positive = total_positive;
  return terms;
}

int64_t CountMultiplyAccumulates(const SsdConfig& config) {
  int64_t macs = 0;
  int width = config.InputWidth(), height = config.InputHeight();
  const int boxes = config.boxes.BoxesPerCell();
  const int classes = config.NumClassesWithBackground();
  const std::vector<ConvSpec> specs = BackboneSpec(config.base_channels);
  for (const ConvSpec& spec : specs) {
    if (spec.stride == 2) {
      width = (width + 1) / 2;
      height = (height + 1) / 2;
    }
    const int64_t cells = int64_t{width} * height;
    // The stem of rgbh-learned reads 4 channels (the compression folded in, see forward()).
    const bool folded_stem =
        &spec == &specs.front() && config.encoding == InputEncoding::kRgbhLearned;
    macs += cells * spec.out_channels * (spec.in_channels + (folded_stem ? 1 : 0)) * 9;
    if (spec.feature_map) macs += cells * boxes * (4 + classes) * spec.out_channels * 9;
  }
  return macs;
}

}  // namespace stereodet::internal
