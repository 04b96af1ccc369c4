// INTERNAL to the models module (includes LibTorch): the SSD network and the MultiBox loss. Only
// ssd_net.cc and ssd.cc include this header; everything else uses ssd.h.
#ifndef STEREODET_MODELS_SSD_SSD_NET_H_
#define STEREODET_MODELS_SSD_SSD_NET_H_

#include <torch/torch.h>

#include <cstdint>
#include <utility>
#include <vector>

#include "stereodet/models/distributed.h"
#include "stereodet/models/ssd/ssd_model.h"

namespace stereodet::internal {

// One 3x3 convolution (padding 1) + batch norm + ReLU of the backbone.
struct ConvSpec {
  int in_channels = 0;
  int out_channels = 0;
  int stride = 1;
  bool feature_map = false;  // its output feeds a head (and the next layer)
};

// The backbone for `base_channels` b (all 3x3):
//   3->b s2 (the stem), b->2b s2, 2b->2b, 2b->4b s2, 4b->4b [map 1, stride 8]
//   4b->8b s2, 8b->8b [map 2, stride 16]   8b->8b s2 [map 3, stride 32]   8b->8b s2 [map 4, stride
//   64]
std::vector<ConvSpec> BackboneSpec(int base_channels);

class SsdNetImpl : public torch::nn::Module {
 public:
  explicit SsdNetImpl(const SsdConfig& config);

  // input: [N, NetworkInputChannels, H, W] in [0, 1]. Returns box deltas [N, boxes, 4] and class
  // logits [N, boxes, classes + 1], boxes in GenerateDefaultBoxes order.
  std::pair<torch::Tensor, torch::Tensor> forward(torch::Tensor input);

  // The stem convolution's output (before batch norm), [N, b, ceil(H/2), ceil(W/2)]: for
  // rgbh-learned the compression folded into the stem.
  torch::Tensor Stem(const torch::Tensor& input);

  int64_t CompressionParameterCount() const;
  const torch::Tensor& compress() const { return compress_; }  // [2, 3], rgbh-learned only
  torch::nn::Conv2d stem() const { return stem_; }             // shares the module

 private:
  bool learned_compression_;
  // rgbh-learned only: the 1x1 convolution's weights [2, 3] (no bias: batch norm follows). It is
  // applied folded into the stem (see forward()), which is exact and costs the stem one more input
  // channel instead of a separate pass over the image.
  torch::Tensor compress_;
  torch::nn::Conv2d stem_{nullptr};    // the first 3x3 stride-2 convolution, 3 -> b channels
  torch::nn::ModuleList stages_;       // Sequential per feature map (the first without the stem)
  torch::nn::ModuleList box_heads_;    // 3x3 conv -> boxes_per_cell * 4
  torch::nn::ModuleList class_heads_;  // 3x3 conv -> boxes_per_cell * (classes + 1)
  int boxes_per_cell_;
  int num_classes_;
};
TORCH_MODULE(SsdNet);

struct MultiBoxLossTerms {
  torch::Tensor total;         // scalar, differentiable
  torch::Tensor localization;  // scalar
  torch::Tensor confidence;    // scalar
  int64_t num_positive = 0;
};

// SSD's MultiBox loss: smooth L1 (beta 1) on the deltas of positives, softmax cross-entropy on the
// positives and on the hard negatives (per image the highest-loss background boxes, negative_ratio
// per positive, at least min_negatives_per_image, never ignored boxes), both divided by max(1,
// positives). pred_deltas [N, B, 4], logits [N, B, C], labels [N, B] int64 (0 bg, >= 1 class, -1
// ignore), target_deltas [N, B, 4]. With a training group, the positives are counted over the
// group's whole batch (this rank's share of its loss); num_positive stays this rank's.
MultiBoxLossTerms MultiBoxLoss(const torch::Tensor& pred_deltas, const torch::Tensor& logits,
                               const torch::Tensor& labels, const torch::Tensor& target_deltas,
                               const MultiBoxLossOptions& options, TrainingGroup* group = nullptr);

// Multiply-accumulates of one forward pass on one image of the config's input size.
int64_t CountMultiplyAccumulates(const SsdConfig& config);

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_SSD_SSD_NET_H_
