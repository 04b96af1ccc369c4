// RpnModel and RpnTrainer: the pimpl boundary between the torch-free API (rpn_model.h) and
// LibTorch, the network's modules and RoIAlign (rpn_net_internal.h).
#include "stereodet/models/rpn/rpn_model.h"

#include <algorithm>
#include <cmath>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/device_internal.h"
#include "stereodet/models/model_handle_internal.h"
#include "stereodet/models/model_json_internal.h"
#include "stereodet/models/rpn/rpn_net_internal.h"
#include "stereodet/models/train_data.h"
#include "stereodet/models/trainer_handle_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

PlanarImage EncodeRpnInput(const cv::Mat& bgr, const cv::Mat& depth_code,
                           const cv::Mat& height_code, RpnInput input,
                           const DepthQuantization& depth) {
  STEREODET_CHECK(bgr.type() == CV_8UC3 && !bgr.empty()) << "the image must be CV_8UC3";
  const bool geometry = input == RpnInput::kRgbd;
  if (geometry) {
    STEREODET_CHECK(depth_code.type() == CV_16UC1 && depth_code.size() == bgr.size() &&
                    height_code.type() == CV_16UC1 && height_code.size() == bgr.size())
        << "depth and height codes must be CV_16UC1 of the image's size";
  }
  PlanarImage out;
  out.channels = RpnInputChannels(input);
  out.rows = bgr.rows;
  out.cols = bgr.cols;
  out.data.resize(static_cast<size_t>(out.channels) * out.rows * out.cols);
  const float depth_scale = 1.0f / static_cast<float>(depth.MaxCode());
  const float height_scale = 1.0f / static_cast<float>(HeightQuantization::kLevels);
  const size_t plane = static_cast<size_t>(out.rows) * out.cols;
  for (int v = 0; v < out.rows; ++v) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = 0; u < out.cols; ++u) {
      const size_t i = static_cast<size_t>(v) * out.cols + u;
      out.data[i] = row[u][2] / 255.0f;
      out.data[plane + i] = row[u][1] / 255.0f;
      out.data[2 * plane + i] = row[u][0] / 255.0f;
      if (geometry) {
        const uint16_t d = depth_code.at<uint16_t>(v, u);
        out.data[3 * plane + i] = std::min(1.0f, d * depth_scale);
        out.data[4 * plane + i] = std::min(1.0f, height_code.at<uint16_t>(v, u) * height_scale);
        out.data[5 * plane + i] = d > 0 ? 1.0f : 0.0f;
      }
    }
  }
  return out;
}

void RpnDetectOptions::Check() const {
  proposals.Check();
  decode.Check();
}

void RpnTrainerOptions::Check() const {
  anchors.Check();
  proposals.Check();
  rois.Check();
  STEREODET_CHECK(weight_decay >= 0.0 && std::isfinite(weight_decay))
      << "weight decay must be >= 0, got " << weight_decay;
}

// --- the network
// ---------------------------------------------------------------------------------

namespace internal {

namespace F = torch::nn::functional;

torch::Tensor RoiAlign(const torch::Tensor& features, const std::vector<std::vector<Box2D>>& rois,
                       double spatial_scale, int pooled, int sampling) {
  STEREODET_CHECK(features.dim() == 4 && features.size(0) == static_cast<int64_t>(rois.size()))
      << "RoiAlign: features must be [N, C, H, W] with one RoI list per image";
  STEREODET_CHECK(pooled >= 1 && sampling >= 1) << "RoiAlign: pooled and sampling must be >= 1";
  const int64_t channels = features.size(1), height = features.size(2), width = features.size(3);
  const int s = pooled * sampling;
  std::vector<torch::Tensor> parts;
  for (size_t b = 0; b < rois.size(); ++b) {
    const int64_t r = static_cast<int64_t>(rois[b].size());
    if (r == 0) continue;
    // One grid for all of the image's RoIs, stacked along the grid's rows, so the feature map is
    // sampled in one call and never copied per RoI.
    std::vector<float> grid(static_cast<size_t>(r) * s * s * 2);
    for (int64_t k = 0; k < r; ++k) {
      const Box2D& box = rois[b][k];
      const double x0 = box.left * spatial_scale - 0.5, y0 = box.top * spatial_scale - 0.5;
      const double w = box.Width() * spatial_scale, h = box.Height() * spatial_scale;
      for (int a = 0; a < s; ++a) {
        const double y = y0 + (a + 0.5) / s * h;
        const float gy = static_cast<float>((2.0 * y + 1.0) / height - 1.0);
        for (int c = 0; c < s; ++c) {
          const double x = x0 + (c + 0.5) / s * w;
          float* g = grid.data() + ((static_cast<size_t>(k) * s + a) * s + c) * 2;
          g[0] = static_cast<float>((2.0 * x + 1.0) / width - 1.0);
          g[1] = gy;
        }
      }
    }
    const torch::Tensor grid_t = torch::from_blob(grid.data(), {1, r * s, s, 2}, torch::kFloat32)
                                     .clone()
                                     .to(features.device(), features.scalar_type());
    torch::Tensor sampled = F::grid_sample(features.narrow(0, static_cast<int64_t>(b), 1), grid_t,
                                           F::GridSampleFuncOptions()
                                               .mode(torch::kBilinear)
                                               .padding_mode(torch::kBorder)
                                               .align_corners(false));
    sampled = sampled.view({channels, r, s, s}).permute({1, 0, 2, 3});
    if (sampling > 1) sampled = F::avg_pool2d(sampled, F::AvgPool2dFuncOptions(sampling));
    parts.push_back(sampled.contiguous());
  }
  if (parts.empty()) return torch::zeros({0, channels, pooled, pooled}, features.options());
  return torch::cat(parts, 0);
}

ResidualBlockImpl::ResidualBlockImpl(int in_channels, int out_channels, int stride) {
  namespace nn = torch::nn;
  conv1 = register_module(
      "conv1",
      nn::Conv2d(
          nn::Conv2dOptions(in_channels, out_channels, 3).stride(stride).padding(1).bias(false)));
  bn1 = register_module("bn1", BatchNorm2dSync(out_channels));
  conv2 = register_module(
      "conv2", nn::Conv2d(nn::Conv2dOptions(out_channels, out_channels, 3).padding(1).bias(false)));
  bn2 = register_module("bn2", BatchNorm2dSync(out_channels));
  if (stride != 1 || in_channels != out_channels) {
    shortcut = register_module(
        "shortcut",
        nn::Conv2d(nn::Conv2dOptions(in_channels, out_channels, 1).stride(stride).bias(false)));
    shortcut_bn = register_module("shortcut_bn", BatchNorm2dSync(out_channels));
  }
}

torch::Tensor ResidualBlockImpl::forward(const torch::Tensor& x) {
  torch::Tensor y = torch::relu(bn1(conv1(x)));
  y = bn2(conv2(y));
  const torch::Tensor identity = shortcut ? shortcut_bn(shortcut(x)) : x;
  return torch::relu(y + identity);
}

TrunkImpl::TrunkImpl(int in_channels, int base, int blocks, int last_stride) {
  namespace nn = torch::nn;
  stem = register_module(
      "stem", nn::Conv2d(nn::Conv2dOptions(in_channels, base, 7).stride(2).padding(3).bias(false)));
  stem_bn = register_module("stem_bn", BatchNorm2dSync(base));
  stages = nn::Sequential();
  int channels = base;
  for (int stage = 0; stage < 3; ++stage) {
    const int out = base << stage;
    for (int b = 0; b < blocks; ++b) {
      const int stride = (stage == 1 || (stage == 2 && last_stride == 16)) && b == 0 ? 2 : 1;
      stages->push_back(ResidualBlock(channels, out, stride));
      channels = out;
    }
  }
  stages = register_module("stages", stages);
}

torch::Tensor TrunkImpl::forward(const torch::Tensor& x) {
  torch::Tensor y = torch::relu(stem_bn(stem(x)));
  y = F::max_pool2d(y, F::MaxPool2dFuncOptions(3).stride(2).padding(1));
  return stages->forward(y);
}

RpnNetImpl::RpnNetImpl(const RpnConfig& c) : config(c) {
  namespace nn = torch::nn;
  const int channels = c.FeatureChannels();
  image = register_module("image", Trunk(3, c.image_width, c.blocks_per_stage, c.feature_stride));
  if (c.input == RpnInput::kRgbd) {
    geometry = register_module("geometry",
                               Trunk(3, c.geometry_width, c.blocks_per_stage, c.feature_stride));
    // Late fusion: the two branches' last stages, concatenated, reduced by a 1x1 convolution.
    fuse = register_module(
        "fuse", nn::Conv2d(nn::Conv2dOptions(channels + 4 * c.geometry_width, channels, 1)));
  }
  const int anchors = c.anchors.AnchorsPerCell();
  rpn_conv =
      register_module("rpn_conv", nn::Conv2d(nn::Conv2dOptions(channels, channels, 3).padding(1)));
  rpn_objectness =
      register_module("rpn_objectness", nn::Conv2d(nn::Conv2dOptions(channels, anchors, 1)));
  rpn_deltas =
      register_module("rpn_deltas", nn::Conv2d(nn::Conv2dOptions(channels, 4 * anchors, 1)));
  const int flat = channels * c.pooled_size * c.pooled_size;
  fc1 = register_module("fc1", nn::Linear(flat, c.head_channels));
  fc2 = register_module("fc2", nn::Linear(c.head_channels, c.head_channels));
  cls = register_module("cls", nn::Linear(c.head_channels, c.NumClasses() + 1));
  box = register_module("box", nn::Linear(c.head_channels, 4 * c.NumClasses()));
  // Faster R-CNN's initialisation of the output layers: small, so the first steps neither
  // saturate the objectness nor throw boxes across the image.
  torch::NoGradGuard no_grad;
  for (auto [module, std] : {std::pair<torch::nn::Module*, double>{rpn_conv.get(), 0.01},
                             {rpn_objectness.get(), 0.01},
                             {rpn_deltas.get(), 0.01},
                             {cls.get(), 0.01},
                             {box.get(), 0.001}}) {
    for (auto& p : module->named_parameters(false)) {
      if (p.key() == "weight") {
        p.value().normal_(0.0, std);
      } else {
        p.value().zero_();
      }
    }
  }
}

torch::Tensor RpnNetImpl::Features(const torch::Tensor& x) {
  if (config.input == RpnInput::kRgb) return image(x);
  const torch::Tensor a = image(x.narrow(1, 0, 3));
  const torch::Tensor g = geometry(x.narrow(1, 3, 3));
  return torch::relu(fuse(torch::cat({a, g}, 1)));
}

std::pair<torch::Tensor, torch::Tensor> RpnNetImpl::Rpn(const torch::Tensor& features) {
  const torch::Tensor h = torch::relu(rpn_conv(features));
  const int64_t b = features.size(0), fh = features.size(2), fw = features.size(3);
  const int64_t a = config.anchors.AnchorsPerCell();
  // [B, A, H, W] -> [B, H, W, A]: GenerateRpnAnchors' order [row][column][anchor].
  torch::Tensor objectness = rpn_objectness(h).permute({0, 2, 3, 1}).reshape({b, fh * fw * a});
  torch::Tensor deltas =
      rpn_deltas(h).view({b, a, 4, fh, fw}).permute({0, 3, 4, 1, 2}).reshape({b, fh * fw * a, 4});
  return {objectness, deltas};
}

std::pair<torch::Tensor, torch::Tensor> RpnNetImpl::Head(const torch::Tensor& pooled) {
  torch::Tensor h = pooled.flatten(1);
  h = torch::relu(fc1(h));
  h = torch::relu(fc2(h));
  return {cls(h), box(h)};
}

}  // namespace internal

// --- RpnModel
// ---------------------------------------------------------------------------------------

namespace {

std::vector<Box2D> BoxesOf(const std::vector<ScoredBox>& boxes) {
  std::vector<Box2D> out;
  out.reserve(boxes.size());
  for (const ScoredBox& b : boxes) out.push_back(b.box);
  return out;
}

}  // namespace

struct internal::RpnModelImpl {
  RpnModelImpl(const RpnConfig& c, ComputeDevice d)
      : config(c),
        device(internal::TorchDevice(d)),
        anchors(GenerateRpnAnchors(c.FeatureWidth(), c.FeatureHeight(), c.anchors)),
        net(c) {
    net->to(device);
  }

  RpnConfig config;
  StereoOptions stereo;
  torch::Device device;
  std::vector<Box2D> anchors;
  mutable internal::RpnNet net;

  // What ModelHandle asks of a family (model_handle_internal.h).
  static RpnConfig ConfigFromJson(const std::string& text, const std::string& source) {
    return RpnConfigFromJson(text, source);
  }
  void ReadModelJson(const std::string& text, const std::string& source) {
    stereo = ReadRpnStereoRecord(text, source);
  }
  int InputChannels() const { return RpnInputChannels(config.input); }
  std::string ModelJson(const WeightsRecord& weights) const {
    return RpnConfigToJson(config, weights,
                           config.input == RpnInput::kRgbd ? std::optional(stereo) : std::nullopt);
  }

  torch::Tensor ToTensor(const std::vector<PlanarImage>& inputs) const {
    const int c = RpnInputChannels(config.input);
    std::vector<float> planar = StackPlanar(inputs, c, config.input_height, config.input_width);
    return torch::from_blob(
               planar.data(),
               {static_cast<int64_t>(inputs.size()), c, config.input_height, config.input_width},
               torch::kFloat32)
        .clone()
        .to(device);
  }

  // Per image, the proposals of the RPN's outputs (scores: the objectness logits).
  std::vector<std::vector<ScoredBox>> Proposals(const torch::Tensor& objectness,
                                                const torch::Tensor& deltas,
                                                const ProposalOptions& options) const {
    const torch::Tensor o = objectness.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    const torch::Tensor d = deltas.detach().to(torch::kCPU, torch::kFloat32).contiguous();
    const int64_t n = static_cast<int64_t>(anchors.size());
    std::vector<std::vector<ScoredBox>> out(o.size(0));
    for (int64_t b = 0; b < o.size(0); ++b) {
      out[b] = SelectProposals(o.data_ptr<float>() + b * n, d.data_ptr<float>() + b * n * 4,
                               anchors, config.input_width, config.input_height, options);
    }
    return out;
  }
};

template class ModelHandle<RpnModel, RpnConfig, internal::RpnModelImpl>;

const StereoOptions& RpnModel::stereo() const { return impl_->stereo; }
void RpnModel::set_stereo(const StereoOptions& stereo) {
  stereo.Check();
  impl_->stereo = stereo;
}
const std::vector<Box2D>& RpnModel::anchors() const { return impl_->anchors; }

std::vector<std::vector<ScoredBox>> RpnModel::Propose(const std::vector<PlanarImage>& inputs,
                                                      const ProposalOptions& options) const {
  if (inputs.empty()) return {};
  torch::NoGradGuard no_grad;
  impl_->net->eval();
  const torch::Tensor features = impl_->net->Features(impl_->ToTensor(inputs));
  const auto [objectness, deltas] = impl_->net->Rpn(features);
  internal::CheckFiniteRows(objectness, "objectness scores");
  internal::CheckFiniteRows(deltas, "proposal offsets");
  std::vector<std::vector<ScoredBox>> proposals = impl_->Proposals(objectness, deltas, options);
  for (auto& image : proposals) {
    for (ScoredBox& p : image) p.score = 1.0f / (1.0f + std::exp(-p.score));
  }
  return proposals;
}

std::vector<std::vector<ScoredBox>> RpnModel::Detect(const std::vector<PlanarImage>& inputs,
                                                     const RpnDetectOptions& options) const {
  options.Check();
  if (inputs.empty()) return {};
  torch::NoGradGuard no_grad;
  impl_->net->eval();
  const RpnConfig& c = impl_->config;
  const torch::Tensor features = impl_->net->Features(impl_->ToTensor(inputs));
  const auto [objectness, deltas] = impl_->net->Rpn(features);
  internal::CheckFiniteRows(objectness, "objectness scores");
  internal::CheckFiniteRows(deltas, "proposal offsets");
  const std::vector<std::vector<ScoredBox>> proposals =
      impl_->Proposals(objectness, deltas, options.proposals);
  std::vector<std::vector<Box2D>> rois(proposals.size());
  for (size_t b = 0; b < proposals.size(); ++b) rois[b] = BoxesOf(proposals[b]);
  std::vector<std::vector<ScoredBox>> detections(inputs.size());
  const torch::Tensor pooled =
      internal::RoiAlign(features, rois, 1.0 / c.feature_stride, c.pooled_size, c.sampling_ratio);
  if (pooled.size(0) == 0) return detections;
  const auto [logits, box] = impl_->net->Head(pooled);
  std::vector<size_t> image_of_roi;  // the head's rows are the images' regions, image by image
  for (size_t b = 0; b < rois.size(); ++b)
    image_of_roi.insert(image_of_roi.end(), rois[b].size(), b);
  internal::CheckFiniteRows(logits, "class scores", image_of_roi);
  internal::CheckFiniteRows(box, "box offsets", image_of_roi);
  const torch::Tensor probabilities =
      torch::softmax(logits, 1).to(torch::kCPU, torch::kFloat32).contiguous();
  const torch::Tensor box_host = box.to(torch::kCPU, torch::kFloat32).contiguous();
  const int k = c.NumClasses();
  int64_t offset = 0;
  for (size_t b = 0; b < rois.size(); ++b) {
    detections[b] = DecodeRpnDetections(rois[b], probabilities.data_ptr<float>() + offset * (k + 1),
                                        box_host.data_ptr<float>() + offset * k * 4, k,
                                        c.input_width, c.input_height, options.decode);
    offset += static_cast<int64_t>(rois[b].size());
  }
  return detections;
}

int64_t RpnModel::ImageBranchParameterCount() const {
  return internal::CountParameters(*impl_->net->image);
}
int64_t RpnModel::GeometryBranchParameterCount() const {
  return impl_->net->geometry ? internal::CountParameters(*impl_->net->geometry) : 0;
}

int RpnModel::InitFrom(const RpnModel& rgb, bool geometry_too) {
  const RpnConfig& src = rgb.config();
  const RpnConfig& dst = impl_->config;
  STEREODET_CHECK(src.input == RpnInput::kRgb) << "--init-from needs an rgb model";
  STEREODET_CHECK(
      src.image_width == dst.image_width && src.blocks_per_stage == dst.blocks_per_stage &&
      src.head_channels == dst.head_channels && src.pooled_size == dst.pooled_size &&
      src.feature_stride == dst.feature_stride && src.classes == dst.classes &&
      src.anchors.sizes_px == dst.anchors.sizes_px && src.anchors.ratios == dst.anchors.ratios)
      << "--init-from: the rgb model's image width, blocks, head, feature stride, classes or "
         "anchors "
         "differ from "
         "this model's";
  STEREODET_CHECK(!geometry_too || dst.input != RpnInput::kRgbd ||
                  dst.geometry_width == dst.image_width)
      << "mirroring into the geometry branch needs geometry_width == image_width";
  torch::NoGradGuard no_grad;
  // Handles to this model's tensors: copy_ into them writes the weights in place.
  torch::OrderedDict<std::string, torch::Tensor> params = impl_->net->named_parameters(true);
  torch::OrderedDict<std::string, torch::Tensor> buffers = impl_->net->named_buffers(true);
  auto find = [&](const std::string& name) -> torch::Tensor* {
    if (torch::Tensor* t = params.find(name)) return t;
    return buffers.find(name);
  };
  int copied = 0;
  auto copy_all = [&](const torch::OrderedDict<std::string, torch::Tensor>& from) {
    for (const auto& item : from) {
      std::vector<std::string> targets = {item.key()};
      if (geometry_too && impl_->net->geometry && item.key().rfind("image.", 0) == 0) {
        targets.push_back("geometry." + item.key().substr(6));
      }
      for (const std::string& name : targets) {
        torch::Tensor* t = find(name);
        STEREODET_CHECK(t != nullptr && t->sizes() == item.value().sizes())
            << "--init-from: no tensor " << name << " of the same shape in this model";
        t->copy_(item.value().to(impl_->device));
        ++copied;
      }
    }
  };
  copy_all(rgb.impl_->net->named_parameters(true));
  copy_all(rgb.impl_->net->named_buffers(true));
  if (impl_->net->fuse) {
    // The fusion starts as "image features only" ([I | 0], no bias), so the RGB-D model begins
    // as the RGB model it mirrors and learns from there how much of the geometry to mix in.
    torch::Tensor weight = impl_->net->fuse->weight;
    weight.zero_();
    const int64_t c = dst.FeatureChannels();
    weight.narrow(1, 0, c).copy_(torch::eye(c).view({c, c, 1, 1}).to(impl_->device));
    impl_->net->fuse->bias.zero_();
  }
  return copied;
}

// --- RpnTrainer
// -------------------------------------------------------------------------------------

struct internal::RpnTrainerImpl : TrainerCore {
  RpnTrainerImpl(RpnModel& m, const RpnTrainerOptions& o)
      : TrainerCore(*m.impl_->net, m.impl_->device, RpnConfigToJson(m.config()), o.weight_decay),
        model(m),
        options(o) {}
  RpnModel& model;
  RpnTrainerOptions options;
};

template class TrainerHandle<internal::RpnTrainerImpl>;

namespace {

std::unique_ptr<internal::RpnTrainerImpl> NewTrainerImpl(RpnModel& model,
                                                         const RpnTrainerOptions& options) {
  options.Check();
  return std::make_unique<internal::RpnTrainerImpl>(model, options);
}

}  // namespace

RpnTrainer::RpnTrainer(RpnModel& model, const RpnTrainerOptions& options)
    : TrainerHandle(internal::HandleOwned(NewTrainerImpl(model, options))) {}

RpnLossParts RpnTrainer::Step(const RpnBatch& batch, double learning_rate, uint64_t step_seed) {
  impl_->SetLearningRate(learning_rate);
  STEREODET_CHECK(!batch.inputs.empty() && batch.inputs.size() == batch.objects.size())
      << "a batch needs inputs and one object list per input";
  STEREODET_CHECK(batch.sampling_seeds.empty() ||
                  batch.sampling_seeds.size() == batch.inputs.size())
      << "a batch of " << batch.inputs.size() << " inputs has " << batch.sampling_seeds.size()
      << " sampling seeds";
  TrainingGroup* const group = impl_->group;
  namespace F = torch::nn::functional;
  torch::manual_seed(step_seed);
  // One sampling stream per image, so that an image's anchors and RoIs are drawn alike whichever
  // rank of a training group trains on it and whatever the images before it drew.
  std::vector<std::mt19937_64> rngs;
  for (size_t i = 0; i < batch.inputs.size(); ++i) {
    rngs.emplace_back(batch.sampling_seeds.empty() ? SampleSeed(step_seed, 0, static_cast<int>(i))
                                                   : batch.sampling_seeds[i]);
  }
  RpnModel::Impl& m = *impl_->model.impl_;
  const RpnConfig& c = m.config;
  const torch::Device device = m.device;
  m.net->train();
  impl_->optimizer.zero_grad();

  const torch::Tensor features = m.net->Features(m.ToTensor(batch.inputs));
  const auto [objectness, deltas] = m.net->Rpn(features);
  const int64_t b = static_cast<int64_t>(batch.inputs.size());
  const int64_t n = static_cast<int64_t>(m.anchors.size());

  // Anchor targets (host), then the sampled anchors' losses.
  std::vector<int64_t> anchor_labels(b * n);
  std::vector<float> anchor_deltas(b * n * 4);
  RpnLossParts parts;
  for (int64_t i = 0; i < b; ++i) {
    const RpnAnchorTargets t =
        SampleAnchors(m.anchors, batch.objects[i], impl_->options.anchors, rngs[i]);
    std::copy(t.labels.begin(), t.labels.end(), anchor_labels.begin() + i * n);
    std::copy(t.deltas.begin(), t.deltas.end(), anchor_deltas.begin() + i * n * 4);
    parts.positive_anchors += t.num_positive;
  }
  const torch::Tensor labels_t =
      torch::from_blob(anchor_labels.data(), {b * n}, torch::kInt64).clone().to(device);
  const torch::Tensor deltas_t =
      torch::from_blob(anchor_deltas.data(), {b * n, 4}, torch::kFloat32).clone().to(device);
  const torch::Tensor sampled = labels_t.ge(0);
  const torch::Tensor positive = labels_t.eq(1);
  // Sums over this rank's images divided by the whole batch's counts: the ranks' losses add up.
  const double num_sampled = std::max(
      1.0, internal::GlobalCount(group, static_cast<double>(sampled.sum().item<int64_t>())));
  const torch::Tensor obj_flat = objectness.reshape({b * n});
  const torch::Tensor objectness_loss =
      F::binary_cross_entropy_with_logits(
          obj_flat.masked_select(sampled), labels_t.masked_select(sampled).to(torch::kFloat32),
          F::BinaryCrossEntropyWithLogitsFuncOptions().reduction(torch::kSum)) /
      num_sampled;
  const torch::Tensor pos_index = positive.nonzero().squeeze(1);
  const torch::Tensor rpn_box_loss =
      F::smooth_l1_loss(deltas.reshape({b * n, 4}).index_select(0, pos_index),
                        deltas_t.index_select(0, pos_index),
                        F::SmoothL1LossFuncOptions().reduction(torch::kSum).beta(1.0 / 9.0)) /
      num_sampled;

  // Proposals from the current RPN (no gradient through them), RoI sampling, the head.
  const std::vector<std::vector<ScoredBox>> proposals =
      m.Proposals(objectness, deltas, impl_->options.proposals);
  std::vector<std::vector<Box2D>> rois(b);
  std::vector<int64_t> roi_labels;
  std::vector<float> roi_deltas;
  for (int64_t i = 0; i < b; ++i) {
    RoiTargets t = SampleRois(proposals[i], batch.objects[i], impl_->options.rois, rngs[i]);
    rois[i] = std::move(t.rois);
    roi_labels.insert(roi_labels.end(), t.labels.begin(), t.labels.end());
    roi_deltas.insert(roi_deltas.end(), t.deltas.begin(), t.deltas.end());
    parts.foreground_rois += t.num_foreground;
  }
  torch::Tensor total = objectness_loss + rpn_box_loss;
  torch::Tensor head_class_loss = torch::zeros({}, features.options());
  torch::Tensor head_box_loss = torch::zeros({}, features.options());
  const int64_t r = static_cast<int64_t>(roi_labels.size());
  const double rois_in_batch = internal::GlobalCount(group, static_cast<double>(r));
  if (r > 0) {
    const torch::Tensor pooled =
        internal::RoiAlign(features, rois, 1.0 / c.feature_stride, c.pooled_size, c.sampling_ratio);
    const auto [logits, box] = m.net->Head(pooled);
    const torch::Tensor roi_labels_t =
        torch::from_blob(roi_labels.data(), {r}, torch::kInt64).clone().to(device);
    const torch::Tensor roi_deltas_t =
        torch::from_blob(roi_deltas.data(), {r, 4}, torch::kFloat32).clone().to(device);
    head_class_loss = F::cross_entropy(logits, roi_labels_t,
                                       F::CrossEntropyFuncOptions().reduction(torch::kSum)) /
                      rois_in_batch;
    const torch::Tensor fg = roi_labels_t.gt(0).nonzero().squeeze(1);
    if (fg.numel() > 0) {
      const torch::Tensor fg_labels = roi_labels_t.index_select(0, fg) - 1;
      const torch::Tensor predicted = box.view({r, c.NumClasses(), 4})
                                          .index_select(0, fg)
                                          .gather(1, fg_labels.view({-1, 1, 1}).expand({-1, 1, 4}))
                                          .squeeze(1);
      head_box_loss =
          F::smooth_l1_loss(predicted, roi_deltas_t.index_select(0, fg),
                            F::SmoothL1LossFuncOptions().reduction(torch::kSum).beta(1.0)) /
          rois_in_batch;
    }
    total = total + head_class_loss + head_box_loss;
  }
  internal::Backward(total, impl_->reducer.get());
  impl_->optimizer.step();
  parts.total = total.item<double>();
  parts.objectness = objectness_loss.item<double>();
  parts.rpn_box = rpn_box_loss.item<double>();
  parts.head_class = head_class_loss.item<double>();
  parts.head_box = head_box_loss.item<double>();
  return parts;
}

}  // namespace stereodet
