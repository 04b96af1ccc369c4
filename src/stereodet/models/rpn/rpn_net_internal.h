// The two-stage detector's LibTorch modules and RoIAlign, for rpn_model.cc and its tests only.
// Includes LibTorch.
#ifndef STEREODET_MODELS_RPN_RPN_NET_INTERNAL_H_
#define STEREODET_MODELS_RPN_RPN_NET_INTERNAL_H_

#include <torch/torch.h>

#include <utility>
#include <vector>

#include "stereodet/geometry/box.h"
#include "stereodet/models/distributed_internal.h"
#include "stereodet/models/rpn/rpn_model.h"

namespace stereodet::internal {

// RoIAlign on grid_sample: `features` is [N, C, H, W]; rois[n] are image n's boxes in input px
// (feature px = input px * spatial_scale). Each RoI is split into pooled x pooled cells; a cell's
// value is the mean of sampling x sampling bilinear samples at the centres of a regular
// sub-grid of the cell. Feature px k covers [k, k + 1) in feature coordinates, its value sits at
// k + 0.5 (torchvision's aligned=True convention: a sample at input px x reads feature coordinate
// x * spatial_scale - 0.5, with pixel centres at integers); samples outside the map read the
// nearest border value (grid_sample's border padding). Returns [sum of RoIs, C, pooled, pooled],
// the RoIs in image order. Differentiable with respect to `features`; on the CPU its backward
// runs one image at a time, each a serial scatter, so gradients are deterministic.
torch::Tensor RoiAlign(const torch::Tensor& features, const std::vector<std::vector<Box2D>>& rois,
                       double spatial_scale, int pooled, int sampling);

// conv3x3 - BN - ReLU - conv3x3 - BN, plus the input (through a strided 1x1 conv + BN when the
// shape changes), then ReLU: ResNet's basic block.
struct ResidualBlockImpl : torch::nn::Module {
  ResidualBlockImpl(int in_channels, int out_channels, int stride);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, shortcut{nullptr};
  BatchNorm2dSync bn1{nullptr}, bn2{nullptr}, shortcut_bn{nullptr};
};
TORCH_MODULE(ResidualBlock);

// ResNet-style trunk to stride 16: 7x7 stride-2 stem + BN + ReLU, 3x3 stride-2 max pool, then
// stages of `blocks` residual blocks at base, 2 base and 4 base channels (strides 4, 8, 16; with
// last_stride 8 the third stage keeps stride 8).
struct TrunkImpl : torch::nn::Module {
  TrunkImpl(int in_channels, int base, int blocks, int last_stride = 16);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Conv2d stem{nullptr};
  BatchNorm2dSync stem_bn{nullptr};
  torch::nn::Sequential stages{nullptr};
};
TORCH_MODULE(Trunk);

struct RpnNetImpl : torch::nn::Module {
  explicit RpnNetImpl(const RpnConfig& config);
  // [B, 3 or 6, H, W] -> the (fused) features [B, FeatureChannels, H / stride, W / stride].
  torch::Tensor Features(const torch::Tensor& x);
  // Objectness logits [B, N] and deltas [B, N, 4], N anchors in GenerateRpnAnchors' order.
  std::pair<torch::Tensor, torch::Tensor> Rpn(const torch::Tensor& features);
  // [R, C, P, P] -> class logits [R, K + 1] and per-class deltas [R, K * 4].
  std::pair<torch::Tensor, torch::Tensor> Head(const torch::Tensor& pooled);

  RpnConfig config;
  Trunk image{nullptr}, geometry{nullptr};
  torch::nn::Conv2d fuse{nullptr};
  BatchNorm2dSync fuse_bn{nullptr};
  torch::nn::Conv2d rpn_conv{nullptr}, rpn_objectness{nullptr}, rpn_deltas{nullptr};
  torch::nn::Linear fc1{nullptr}, fc2{nullptr}, cls{nullptr}, box{nullptr};
};
TORCH_MODULE(RpnNet);

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_RPN_RPN_NET_INTERNAL_H_
