// Det3dModel and Det3dTrainer: the network (pillars, BEV backbone, heads, PSWarp, the auxiliary
// network), its losses and decoding. The one det3d file that includes LibTorch.
#include "stereodet/models/det3d/det3d_model.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include "stereodet/models/checkpoint_internal.h"
#include "stereodet/models/det3d/det3d_net_internal.h"
#include "stereodet/models/device_internal.h"
#include "stereodet/models/distributed_internal.h"
#include "stereodet/models/model_handle_internal.h"
#include "stereodet/models/model_json_internal.h"
#include "stereodet/models/trainer_handle_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

Det3dSample MakeDet3dSample(const Det3dFrame& frame, const Det3dConfig& config,
                            const std::vector<LidarBox>& anchors, bool with_targets,
                            int max_aux_points) {
  Det3dSample sample;
  sample.pillars = Pillarize(frame.points, config.grid);
  if (!with_targets) return sample;
  std::vector<int> anchor_class(anchors.size());
  for (size_t i = 0; i < anchors.size(); ++i) anchor_class[i] = anchors[i].label;
  sample.anchors = AssignAnchors(anchors, anchor_class, config.AnchorClasses(), frame.boxes);
  const size_t n = sample.pillars.xyz.size() / 3;
  const size_t keep = max_aux_points > 0 ? std::min<size_t>(n, max_aux_points) : n;
  sample.aux_xyz.reserve(keep * 3);
  for (size_t k = 0; k < keep; ++k) {
    const size_t i = k * n / keep;  // an even subsample, deterministic
    sample.aux_xyz.insert(sample.aux_xyz.end(), sample.pillars.xyz.begin() + 3 * i,
                          sample.pillars.xyz.begin() + 3 * i + 3);
  }
  sample.points = AuxiliaryTargets(sample.aux_xyz, frame.boxes);
  return sample;
}

void Det3dDecodeOptions::Check() const {
  nms.Check();
  STEREODET_CHECK(score_threshold >= 0.0f && score_threshold <= 1.0f)
      << "score threshold must be in [0, 1], got " << score_threshold;
}

void Det3dLossOptions::Check() const {
  for (double w :
       {box_weight, direction_weight, part_warp_weight, segmentation_weight, centre_weight}) {
    STEREODET_CHECK(w >= 0.0 && std::isfinite(w)) << "loss weights must be >= 0, got " << w;
  }
}

// --- The network ---------------------------------------------------------------------------------

namespace internal {
namespace {

torch::nn::Sequential ConvBlock(int in, int out, int stride, int layers) {
  torch::nn::Sequential s;
  for (int i = 0; i < layers; ++i) {
    s->push_back(torch::nn::Conv2d(torch::nn::Conv2dOptions(i == 0 ? in : out, out, 3)
                                       .stride(i == 0 ? stride : 1)
                                       .padding(1)
                                       .bias(false)));
    s->push_back(BatchNorm2dSync(out));
    s->push_back(torch::nn::ReLU());
  }
  return s;
}

torch::nn::Sequential UpBlock(int in, int out, int factor) {
  torch::nn::Sequential s;
  if (factor == 1) {
    s->push_back(torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, 1).bias(false)));
  } else {
    s->push_back(torch::nn::ConvTranspose2d(
        torch::nn::ConvTranspose2dOptions(in, out, factor).stride(factor).bias(false)));
  }
  s->push_back(BatchNorm2dSync(out));
  s->push_back(torch::nn::ReLU());
  return s;
}

}  // namespace

struct Det3dNetImpl : torch::nn::Module {
  explicit Det3dNetImpl(const Det3dConfig& config)
      : num_classes(static_cast<int>(config.classes.size())),
        anchors_per_cell(num_classes * kAnchorRotations),
        parts(config.parts_l * config.parts_w) {
    const int c = config.base_channels;
    pfn_linear = register_module(
        "pfn_linear", torch::nn::Linear(torch::nn::LinearOptions(kPillarFeatures, c).bias(false)));
    pfn_bn = register_module("pfn_bn", BatchNorm1dSync(c));
    block1 = register_module("block1", ConvBlock(c, c, 2, 2));
    block2 = register_module("block2", ConvBlock(c, 2 * c, 2, 2));
    block3 = register_module("block3", ConvBlock(2 * c, 4 * c, 2, 2));
    up1 = register_module("up1", UpBlock(c, 2 * c, 1));
    up2 = register_module("up2", UpBlock(2 * c, 2 * c, 2));
    up3 = register_module("up3", UpBlock(4 * c, 2 * c, 4));
    const int head_in = 6 * c;
    auto head = [&](const char* name, int out) {
      return register_module(name, torch::nn::Conv2d(torch::nn::Conv2dOptions(head_in, out, 1)));
    };
    cls_head = head("cls_head", anchors_per_cell);
    box_head = head("box_head", anchors_per_cell * kBoxCodeSize);
    dir_head = head("dir_head", anchors_per_cell * 2);
    psw_head = head("psw_head", num_classes * parts);
    // Focal loss prior: every anchor starts at p = 0.01 foreground (RetinaNet).
    const double prior = -std::log((1.0 - 0.01) / 0.01);
    torch::NoGradGuard no_grad;
    cls_head->bias.fill_(prior);
    psw_head->bias.fill_(prior);
    // The auxiliary network (training only): 7c sampled features + height -> 64 -> seg, offset.
    aux_in_features = 7 * c + 1;
    aux = register_module("aux", torch::nn::Sequential(torch::nn::Linear(7 * c + 1, 64),
                                                       BatchNorm1dSync(64), torch::nn::ReLU()));
    aux_seg = register_module("aux_seg", torch::nn::Linear(64, 1));
    aux_offset = register_module("aux_offset", torch::nn::Linear(64, 3));
    aux_seg->bias.fill_(prior);
  }

  int num_classes, anchors_per_cell, parts;
  torch::nn::Linear pfn_linear{nullptr};
  BatchNorm1dSync pfn_bn{nullptr};
  torch::nn::Sequential block1{nullptr}, block2{nullptr}, block3{nullptr};
  torch::nn::Sequential up1{nullptr}, up2{nullptr}, up3{nullptr};
  torch::nn::Conv2d cls_head{nullptr}, box_head{nullptr}, dir_head{nullptr}, psw_head{nullptr};
  torch::nn::Sequential aux{nullptr};
  int64_t aux_in_features = 0;
  torch::nn::Linear aux_seg{nullptr}, aux_offset{nullptr};
};
TORCH_MODULE(Det3dNet);

// The batch as tensors on the device.
struct BatchTensors {
  torch::Tensor point_features;  // [N, 9] of the points kept (a pillar's first M)
  torch::Tensor point_slot;      // [N] int64: pillar * M + slot
  torch::Tensor pillar_cell;     // [P] int64: b * rows * cols + cell
  int64_t num_pillars = 0;
};

BatchTensors ToBatchTensors(const std::vector<Det3dSample>& samples, const Det3dConfig& config,
                            const torch::Device& device) {
  const int64_t cells = static_cast<int64_t>(config.grid.Rows()) * config.grid.Cols();
  const int m = config.max_points_per_pillar;
  std::vector<float> features;
  std::vector<int64_t> slot, pillar_cell;
  for (size_t b = 0; b < samples.size(); ++b) {
    const Pillars& p = samples[b].pillars;
    std::unordered_map<int64_t, std::pair<int64_t, int>> pillar;  // cell -> (index, count)
    for (size_t i = 0; i < p.cell.size(); ++i) {
      auto [it, inserted] =
          pillar.try_emplace(p.cell[i], static_cast<int64_t>(pillar_cell.size()), 0);
      if (inserted) pillar_cell.push_back(static_cast<int64_t>(b) * cells + p.cell[i]);
      const int s = it->second.second++;
      // Points beyond a pillar's first M never reach the max: leave them out here, so that the
      // pillar feature net (and its batch norm's statistics) runs on the points it uses only; a
      // stereo cloud keeps about 30% of its points this way.
      if (s >= m) continue;
      slot.push_back(it->second.first * m + s);
      features.insert(features.end(), p.features.begin() + i * kPillarFeatures,
                      p.features.begin() + (i + 1) * kPillarFeatures);
    }
  }
  BatchTensors t;
  t.num_pillars = static_cast<int64_t>(pillar_cell.size());
  const int64_t n = static_cast<int64_t>(slot.size());
  t.point_features =
      torch::from_blob(features.data(), {n, kPillarFeatures}, torch::kFloat32).clone().to(device);
  t.point_slot = torch::from_blob(slot.data(), {n}, torch::kInt64).clone().to(device);
  t.pillar_cell =
      torch::from_blob(pillar_cell.data(), {t.num_pillars}, torch::kInt64).clone().to(device);
  return t;
}

torch::Tensor ScatterPillars(const torch::Tensor& point_features, const torch::Tensor& point_slot,
                             const torch::Tensor& pillar_cell, int64_t num_pillars, int max_points,
                             int64_t batch, int rows, int cols) {
  const int64_t c = point_features.size(1);
  const torch::Tensor kept = point_slot.ge(0).nonzero().squeeze(1);
  torch::Tensor slots = torch::zeros({num_pillars * max_points, c}, point_features.options());
  slots =
      slots.index_copy(0, point_slot.index_select(0, kept), point_features.index_select(0, kept));
  const torch::Tensor pillar = std::get<0>(slots.view({num_pillars, max_points, c}).max(1));
  torch::Tensor canvas = torch::zeros({batch * rows * cols, c}, point_features.options());
  canvas = canvas.index_copy(0, pillar_cell, pillar);
  return canvas.view({batch, rows, cols, c}).permute({0, 3, 1, 2}).contiguous();
}

torch::Tensor PartSamplingGrid(const torch::Tensor& boxes, const torch::Tensor& part_u,
                               const torch::Tensor& part_v, const BevGridOptions& g) {
  const torch::Tensor x = boxes.select(2, 0).unsqueeze(2), y = boxes.select(2, 1).unsqueeze(2);
  const torch::Tensor l = boxes.select(2, 3).unsqueeze(2), w = boxes.select(2, 4).unsqueeze(2);
  const torch::Tensor c = torch::cos(boxes.select(2, 6)).unsqueeze(2);
  const torch::Tensor s = torch::sin(boxes.select(2, 6)).unsqueeze(2);
  const torch::Tensor u = part_u.view({1, 1, -1}) * l, v = part_v.view({1, 1, -1}) * w;
  const torch::Tensor px = x + c * u - s * v, py = y + s * u + c * v;  // [B, A, P]
  return torch::stack({2.0 * (py - g.min_y_m) / (g.max_y_m - g.min_y_m) - 1.0,
                       2.0 * (px - g.min_x_m) / (g.max_x_m - g.min_x_m) - 1.0},
                      3);
}

struct NetOutputs {
  torch::Tensor cls;                    // [B, A] logits
  torch::Tensor box;                    // [B, A, 7]
  torch::Tensor dir;                    // [B, A, 2]
  torch::Tensor psw;                    // [B, A] logits (part-sensitive warping)
  std::vector<torch::Tensor> features;  // the 3 blocks' maps (auxiliary network)
};

}  // namespace internal

// --- Det3dModel ----------------------------------------------------------------------------------

struct internal::Det3dModelImpl {
  Det3dModelImpl(const Det3dConfig& c, ComputeDevice d)
      : config(c),
        device(d),
        torch_device(internal::TorchDevice(d)),
        anchors(GenerateAnchors(c.grid, Det3dConfig::kHeadStride, c.AnchorClasses())),
        net(c) {
    std::vector<float> a;
    std::vector<int64_t> cls;
    for (const LidarBox& b : anchors) {
      a.insert(a.end(), {float(b.x), float(b.y), float(b.z), float(b.l), float(b.w), float(b.h),
                         float(b.yaw)});
      cls.push_back(b.label);
    }
    const int64_t n = static_cast<int64_t>(anchors.size());
    anchor_tensor = torch::from_blob(a.data(), {n, 7}, torch::kFloat32).clone().to(torch_device);
    anchor_class = torch::from_blob(cls.data(), {n}, torch::kInt64).clone().to(torch_device);
    std::vector<float> pu, pv;
    for (int i = 0; i < c.parts_l; ++i) {
      for (int j = 0; j < c.parts_w; ++j) {
        pu.push_back(static_cast<float>((i + 0.5) / c.parts_l - 0.5));
        pv.push_back(static_cast<float>((j + 0.5) / c.parts_w - 0.5));
      }
    }
    part_u = torch::tensor(pu).to(torch_device);
    part_v = torch::tensor(pv).to(torch_device);
    net->to(torch_device);
  }

  Det3dConfig config;
  ComputeDevice device;
  torch::Device torch_device;
  std::vector<LidarBox> anchors;
  torch::Tensor anchor_tensor, anchor_class, part_u, part_v;
  mutable internal::Det3dNet net;

  // What ModelHandle asks of a family (model_handle_internal.h); model.json holds nothing else.
  static Det3dConfig ConfigFromJson(const std::string& text, const std::string& source) {
    return Det3dConfigFromJson(text, source);
  }
  void ReadModelJson(const std::string& /*text*/, const std::string& /*source*/) {}
  int InputChannels() const { return kPillarFeatures; }
  std::string ModelJson(const WeightsRecord& weights) const {
    return Det3dConfigToJson(config, weights);
  }

  // Decoded boxes [B, A, 7] (x, y, z, l, w, h, yaw) from residuals (box_coder's DecodeBox).
  torch::Tensor Decode(const torch::Tensor& residuals) const {
    const torch::Tensor& a = anchor_tensor;
    const torch::Tensor d = torch::sqrt(a.select(1, 3).pow(2) + a.select(1, 4).pow(2));
    const torch::Tensor r = residuals;
    return torch::stack(
        {a.select(1, 0) + r.select(2, 0) * d, a.select(1, 1) + r.select(2, 1) * d,
         a.select(1, 2) + r.select(2, 2) * a.select(1, 5),
         a.select(1, 3) * torch::exp(r.select(2, 3).clamp(-4, 4)),
         a.select(1, 4) * torch::exp(r.select(2, 4).clamp(-4, 4)),
         a.select(1, 5) * torch::exp(r.select(2, 5).clamp(-4, 4)), a.select(1, 6) + r.select(2, 6)},
        2);
  }

  // PSWarp: the part maps [B, K * P, H, W] sampled at each box's P part centres (boxes [B, A,
  // 7]), channel k * P + p at part p for the anchor's class k, averaged over parts: [B, A].
  torch::Tensor PartWarp(const torch::Tensor& part_maps, const torch::Tensor& boxes) const {
    namespace F = torch::nn::functional;
    // Border padding: the parts of a box that reaches past the canvas read the edge cells, which
    // learn to say "background"; with zeros they would read a fixed logit 0 (p = 0.5) that no
    // weight can change, and the loss of such anchors could never fall.
    const torch::Tensor grid = internal::PartSamplingGrid(boxes, part_u, part_v, config.grid);
    // A NaN or inf sampling position crashes LibTorch's grid_sampler_2d_backward (its index
    // arithmetic overflows) instead of giving a NaN loss; a diverging training gets there first,
    // so it is stopped here rather than with a segfault (the training loop and Detector::Run say
    // which step or frame).
    internal::CheckFiniteRows(grid, "box predictions");
    const torch::Tensor sampled = F::grid_sample(part_maps, grid,
                                                 F::GridSampleFuncOptions()
                                                     .mode(torch::kBilinear)
                                                     .padding_mode(torch::kBorder)
                                                     .align_corners(false));
    // [B, K * P, A, P] -> [B, K, P, A, P] -> diagonal over the two part dimensions: [B, K, A, P].
    const int64_t batch = sampled.size(0), parts = part_u.size(0), num_anchors = sampled.size(2);
    const torch::Tensor diagonal =
        torch::diagonal(sampled.view({batch, -1, parts, num_anchors, parts}), 0, 2, 4);
    const torch::Tensor mean = diagonal.mean(3);  // [B, K, A]
    return mean.gather(1, anchor_class.view({1, 1, -1}).expand({batch, 1, num_anchors})).squeeze(1);
  }

  internal::NetOutputs Forward(const std::vector<Det3dSample>& samples) const {
    const internal::BatchTensors t = internal::ToBatchTensors(samples, config, torch_device);
    const int64_t batch = static_cast<int64_t>(samples.size());
    const int rows = config.grid.Rows(), cols = config.grid.Cols();
    const int m = config.max_points_per_pillar;
    // Pillar feature net: per point, then the max over a pillar's (first M) points. ReLU output is
    // >= 0, so empty slots (0) never win the max.
    torch::Tensor f = torch::relu(net->pfn_bn->forward(net->pfn_linear->forward(t.point_features)));
    const torch::Tensor canvas = internal::ScatterPillars(f, t.point_slot, t.pillar_cell,
                                                          t.num_pillars, m, batch, rows, cols);

    internal::NetOutputs out;
    const torch::Tensor f1 = net->block1->forward(canvas);
    const torch::Tensor f2 = net->block2->forward(f1);
    const torch::Tensor f3 = net->block3->forward(f2);
    out.features = {f1, f2, f3};
    const torch::Tensor x =
        torch::cat({net->up1->forward(f1), net->up2->forward(f2), net->up3->forward(f3)}, 1);
    const int apc = net->anchors_per_cell;
    auto per_anchor = [&](const torch::Tensor& map, int size) {
      // [B, apc * size, H, W] -> [B, H, W, apc, size] -> [B, A, size] (anchor order of
      // GenerateAnchors: cell, class, rotation).
      return map.permute({0, 2, 3, 1}).reshape({batch, -1, size});
    };
    out.cls = per_anchor(net->cls_head->forward(x), 1).squeeze(2);
    out.box = per_anchor(net->box_head->forward(x), kBoxCodeSize);
    out.dir = per_anchor(net->dir_head->forward(x), 2);
    STEREODET_CHECK(out.cls.size(1) == static_cast<int64_t>(anchors.size()))
        << "network emits " << out.cls.size(1) << " anchors, expected " << anchors.size()
        << " (apc " << apc << ")";
    // The boxes the parts are sampled in are the predictions; no gradient flows through them.
    out.psw = PartWarp(net->psw_head->forward(x), Decode(out.box.detach()));
    return out;
  }

  // The auxiliary network on a batch: [N] segmentation logits and [N, 3] centre offsets for the
  // samples' aux_xyz, in sample order; undefined tensors when no sample has points. With a
  // training group, "no sample" means none of the whole batch's (the synchronized batch norm
  // needs every rank): a rank whose slice has none runs the network on zero rows.
  std::pair<torch::Tensor, torch::Tensor> Auxiliary(const std::vector<Det3dSample>& samples,
                                                    const std::vector<torch::Tensor>& maps,
                                                    TrainingGroup* group) const {
    namespace F = torch::nn::functional;
    const BevGridOptions& g = config.grid;
    std::vector<torch::Tensor> rows;
    for (size_t b = 0; b < samples.size(); ++b) {
      const std::vector<float>& xyz = samples[b].aux_xyz;
      const int64_t n = static_cast<int64_t>(xyz.size() / 3);
      if (n == 0) continue;
      const torch::Tensor p =
          torch::from_blob(const_cast<float*>(xyz.data()), {n, 3}, torch::kFloat32)
              .clone()
              .to(torch_device);
      const torch::Tensor grid =
          torch::stack({2.0 * (p.select(1, 1) - g.min_y_m) / (g.max_y_m - g.min_y_m) - 1.0,
                        2.0 * (p.select(1, 0) - g.min_x_m) / (g.max_x_m - g.min_x_m) - 1.0},
                       1)
              .view({1, 1, n, 2});
      std::vector<torch::Tensor> parts;
      for (const torch::Tensor& map : maps) {
        const torch::Tensor s = F::grid_sample(map.narrow(0, static_cast<int64_t>(b), 1), grid,
                                               F::GridSampleFuncOptions()
                                                   .mode(torch::kBilinear)
                                                   .padding_mode(torch::kZeros)
                                                   .align_corners(false));
        parts.push_back(s.view({map.size(1), n}).t());
      }
      parts.push_back(((p.select(1, 2) - g.min_z_m) / (g.max_z_m - g.min_z_m)).unsqueeze(1));
      rows.push_back(torch::cat(parts, 1));
    }
    if (internal::GlobalCount(group, static_cast<double>(rows.size())) == 0) return {};
    if (rows.empty()) {
      rows.push_back(torch::zeros({0, net->aux_in_features}, maps.front().options()));
    }
    const torch::Tensor h = net->aux->forward(torch::cat(rows, 0));
    return {net->aux_seg->forward(h).squeeze(1), net->aux_offset->forward(h)};
  }
};

template class ModelHandle<Det3dModel, Det3dConfig, internal::Det3dModelImpl>;

const std::vector<LidarBox>& Det3dModel::anchors() const { return impl_->anchors; }
ComputeDevice Det3dModel::device() const { return impl_->device; }

std::vector<std::vector<ScoredLidarBox>> Det3dModel::Detect(
    const std::vector<Det3dSample>& samples, const Det3dDecodeOptions& options) const {
  options.Check();
  std::vector<std::vector<ScoredLidarBox>> detections(samples.size());
  if (samples.empty()) return detections;
  torch::NoGradGuard no_grad;
  impl_->net->eval();
  const internal::NetOutputs out = impl_->Forward(samples);
  internal::CheckFiniteRows(out.cls, "class scores");
  internal::CheckFiniteRows(out.psw, "PSWarp scores");
  internal::CheckFiniteRows(out.box, "box offsets");
  internal::CheckFiniteRows(out.dir, "direction scores");
  const torch::Tensor score =
      ((torch::sigmoid(out.cls) + torch::sigmoid(out.psw)) / 2.0).to(torch::kCPU).contiguous();
  const torch::Tensor boxes = impl_->Decode(out.box).to(torch::kCPU).contiguous();
  const torch::Tensor dir = out.dir.argmax(2).to(torch::kCPU).contiguous();
  const int64_t num_anchors = score.size(1);
  for (size_t b = 0; b < samples.size(); ++b) {
    const float* s = score.data_ptr<float>() + b * num_anchors;
    const float* bx = boxes.data_ptr<float>() + b * num_anchors * 7;
    const int64_t* d = dir.data_ptr<int64_t>() + b * num_anchors;
    std::vector<ScoredLidarBox> candidates;
    for (int64_t i = 0; i < num_anchors; ++i) {
      if (s[i] < options.score_threshold) continue;
      const float* v = bx + i * 7;
      ScoredLidarBox c;
      c.box = {.x = v[0],
               .y = v[1],
               .z = v[2],
               .l = v[3],
               .w = v[4],
               .h = v[5],
               .yaw = ApplyDirection(v[6], static_cast<int>(d[i])),
               .label = impl_->anchors[i].label};
      c.score = s[i];
      candidates.push_back(c);
    }
    detections[b] = RotatedNms(candidates, options.nms);
  }
  return detections;
}

int64_t Det3dModel::AuxiliaryParameterCount() const {
  return internal::CountParameters(*impl_->net->aux) +
         internal::CountParameters(*impl_->net->aux_seg) +
         internal::CountParameters(*impl_->net->aux_offset);
}

// --- Det3dTrainer --------------------------------------------------------------------------------

namespace {

// Sigmoid focal loss (RetinaNet, alpha 0.25, gamma 2), summed over entries where weight is 1.
torch::Tensor FocalLoss(const torch::Tensor& logits, const torch::Tensor& targets,
                        const torch::Tensor& weights) {
  const torch::Tensor p = torch::sigmoid(logits);
  const torch::Tensor ce = torch::nn::functional::binary_cross_entropy_with_logits(
      logits, targets,
      torch::nn::functional::BinaryCrossEntropyWithLogitsFuncOptions().reduction(torch::kNone));
  const torch::Tensor pt = p * targets + (1 - p) * (1 - targets);
  const torch::Tensor alpha = 0.25 * targets + 0.75 * (1 - targets);
  return (alpha * (1 - pt).pow(2) * ce * weights).sum();
}

}  // namespace

struct internal::Det3dTrainerImpl : TrainerCore {
  Det3dTrainerImpl(Det3dModelImpl& m, const Det3dLossOptions& o, double weight_decay)
      : TrainerCore(*m.net, m.torch_device, Det3dConfigToJson(m.config), weight_decay),
        model(m),
        options(o) {}

  Det3dModelImpl& model;
  Det3dLossOptions options;

  // With `group`, this rank's share of the group's whole batch's loss: every term divided by the
  // whole batch's positives or foreground points.
  std::pair<torch::Tensor, Det3dLossParts> Loss(const std::vector<Det3dSample>& batch,
                                                TrainingGroup* group) const {
    STEREODET_CHECK(!batch.empty()) << "empty training batch";
    const torch::Device& dev = model.torch_device;
    const int64_t num_anchors = static_cast<int64_t>(model.anchors.size());
    std::vector<int64_t> labels;
    std::vector<float> codes;
    std::vector<int64_t> dirs;
    for (const Det3dSample& s : batch) {
      STEREODET_CHECK(s.anchors.labels.size() == static_cast<size_t>(num_anchors))
          << "sample has targets for " << s.anchors.labels.size() << " anchors, the model has "
          << num_anchors;
      labels.insert(labels.end(), s.anchors.labels.begin(), s.anchors.labels.end());
      codes.insert(codes.end(), s.anchors.box_codes.begin(), s.anchors.box_codes.end());
      dirs.insert(dirs.end(), s.anchors.directions.begin(), s.anchors.directions.end());
    }
    const int64_t b = static_cast<int64_t>(batch.size());
    const torch::Tensor label =
        torch::from_blob(labels.data(), {b, num_anchors}, torch::kInt64).clone().to(dev);
    const torch::Tensor code =
        torch::from_blob(codes.data(), {b, num_anchors, kBoxCodeSize}, torch::kFloat32)
            .clone()
            .to(dev);
    const torch::Tensor dir =
        torch::from_blob(dirs.data(), {b, num_anchors}, torch::kInt64).clone().to(dev);

    const internal::NetOutputs out = model.Forward(batch);
    const torch::Tensor positive = label.gt(0);
    const torch::Tensor cared = label.ge(0).to(torch::kFloat32);
    const torch::Tensor target = positive.to(torch::kFloat32);
    const double num_pos = std::max(
        1.0, internal::GlobalCount(group, static_cast<double>(positive.sum().item<int64_t>())));
    Det3dLossParts parts;
    parts.num_positive = static_cast<int>(positive.sum().item<int64_t>());
    const torch::Tensor cls = FocalLoss(out.cls, target, cared) / num_pos;
    const torch::Tensor psw = FocalLoss(out.psw, target, cared) / num_pos;
    // Box residuals on positives, the yaw as sin(pred - target) (SECOND's sin difference).
    const torch::Tensor pos_f = target.unsqueeze(2);
    torch::Tensor pred = out.box, tgt = code;
    const torch::Tensor pred_yaw = torch::sin(pred.select(2, 6)) * torch::cos(tgt.select(2, 6));
    const torch::Tensor tgt_yaw = torch::cos(pred.select(2, 6)) * torch::sin(tgt.select(2, 6));
    pred = torch::cat({pred.narrow(2, 0, 6), pred_yaw.unsqueeze(2)}, 2);
    tgt = torch::cat({tgt.narrow(2, 0, 6), tgt_yaw.unsqueeze(2)}, 2);
    const torch::Tensor box =
        (torch::nn::functional::smooth_l1_loss(pred, tgt,
                                               torch::nn::functional::SmoothL1LossFuncOptions()
                                                   .reduction(torch::kNone)
                                                   .beta(1.0 / 9.0)) *
         pos_f)
            .sum() /
        num_pos;
    const torch::Tensor dir_ce = torch::nn::functional::cross_entropy(
        out.dir.reshape({-1, 2}), dir.reshape({-1}),
        torch::nn::functional::CrossEntropyFuncOptions().reduction(torch::kNone));
    const torch::Tensor direction = (dir_ce * target.reshape({-1})).sum() / num_pos;
    torch::Tensor total = cls + options.box_weight * box + options.direction_weight * direction +
                          options.part_warp_weight * psw;
    parts.classification = cls.item<double>();
    parts.box = box.item<double>();
    parts.direction = direction.item<double>();
    parts.part_warp = psw.item<double>();
    if (options.auxiliary) {
      auto [seg, offset] = model.Auxiliary(batch, out.features, group);
      if (seg.defined()) {
        std::vector<float> fg, off;
        for (const Det3dSample& s : batch) {
          fg.insert(fg.end(), s.points.foreground.begin(), s.points.foreground.end());
          off.insert(off.end(), s.points.offsets.begin(), s.points.offsets.end());
        }
        const int64_t n = static_cast<int64_t>(fg.size());
        STEREODET_CHECK(n == seg.size(0))
            << "auxiliary targets for " << n << " points, " << seg.size(0) << " sampled";
        const torch::Tensor fg_t =
            torch::from_blob(fg.data(), {n}, torch::kFloat32).clone().to(dev);
        const torch::Tensor off_t =
            torch::from_blob(off.data(), {n, 3}, torch::kFloat32).clone().to(dev);
        const double num_fg =
            std::max(1.0, internal::GlobalCount(group, fg_t.sum().item<double>()));
        const torch::Tensor segmentation = FocalLoss(seg, fg_t, torch::ones_like(fg_t)) / num_fg;
        const torch::Tensor centre =
            (torch::nn::functional::smooth_l1_loss(offset, off_t,
                                                   torch::nn::functional::SmoothL1LossFuncOptions()
                                                       .reduction(torch::kNone)
                                                       .beta(1.0 / 9.0)) *
             fg_t.unsqueeze(1))
                .sum() /
            num_fg;
        total = total + options.segmentation_weight * segmentation + options.centre_weight * centre;
        parts.segmentation = segmentation.item<double>();
        parts.centre = centre.item<double>();
      }
    }
    parts.total = total.item<double>();
    return {total, parts};
  }
};

template class TrainerHandle<internal::Det3dTrainerImpl>;

namespace {

std::unique_ptr<internal::Det3dTrainerImpl> NewTrainerImpl(internal::Det3dModelImpl& model,
                                                           const Det3dLossOptions& loss,
                                                           double weight_decay) {
  loss.Check();
  STEREODET_CHECK(weight_decay >= 0.0) << "weight_decay must be >= 0, got " << weight_decay;
  return std::make_unique<internal::Det3dTrainerImpl>(model, loss, weight_decay);
}

}  // namespace

Det3dTrainer::Det3dTrainer(Det3dModel& model, const Det3dLossOptions& loss, double weight_decay)
    : TrainerHandle(internal::HandleOwned(NewTrainerImpl(*model.impl_, loss, weight_decay))) {}

Det3dLossParts Det3dTrainer::Step(const std::vector<Det3dSample>& batch, double learning_rate) {
  impl_->SetLearningRate(learning_rate);
  impl_->model.net->train();
  impl_->optimizer.zero_grad();
  auto [total, parts] = impl_->Loss(batch, impl_->group);
  internal::Backward(total, impl_->reducer.get());
  impl_->optimizer.step();
  return parts;
}

Det3dLossParts Det3dTrainer::Evaluate(const std::vector<Det3dSample>& batch) const {
  torch::NoGradGuard no_grad;
  impl_->model.net->eval();
  return impl_->Loss(batch, /*group=*/nullptr).second;
}

}  // namespace stereodet
