// Internal tests of the two-stage detector's network (includes LibTorch): RoIAlign by hand and
// against a brute-force bilinear reference (values and gradients), deterministic backward, the
// output layout, the branches' parameter counts, and mirroring an RGB model into an RGB-D one.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stereodet/models/models_test_util.h"
#include "stereodet/models/rpn/rpn_net_internal.h"

namespace stereodet::internal {
namespace {

torch::Tensor Map2x3() {  // one channel: 0 1 2 / 3 4 5
  return torch::arange(6, torch::kFloat32).view({1, 1, 2, 3});
}

TEST(RpnRoiAlignTest, ByHand) {
  // The whole map as one cell, one sample at its centre: feature coordinates (1, 0.5), halfway
  // between 1 and 4.
  torch::Tensor out = RoiAlign(Map2x3(), {{{0, 0, 3, 2}}}, 1.0, 1, 1);
  ASSERT_EQ(out.sizes(), (torch::IntArrayRef{1, 1, 1, 1}));
  EXPECT_FLOAT_EQ(out.item<float>(), 2.5f);
  // 2 x 2 cells, one sample each, at x = 0.25, 1.75 and y = 0, 1.
  out = RoiAlign(Map2x3(), {{{0, 0, 3, 2}}}, 1.0, 2, 1);
  EXPECT_FLOAT_EQ(out[0][0][0][0].item<float>(), 0.25f);
  EXPECT_FLOAT_EQ(out[0][0][0][1].item<float>(), 1.75f);
  EXPECT_FLOAT_EQ(out[0][0][1][0].item<float>(), 3.25f);
  EXPECT_FLOAT_EQ(out[0][0][1][1].item<float>(), 4.75f);
  // One cell, 2 x 2 samples: their mean (0.25 + 1.75 + 3.25 + 4.75) / 4.
  out = RoiAlign(Map2x3(), {{{0, 0, 3, 2}}}, 1.0, 1, 2);
  EXPECT_FLOAT_EQ(out.item<float>(), 2.5f);
  // Outside the map: the border value (x = -0.5 reads column 0; y = 0.5 halfway 0 and 3).
  out = RoiAlign(Map2x3(), {{{-1, 0, 1, 2}}}, 1.0, 1, 1);
  EXPECT_FLOAT_EQ(out.item<float>(), 1.5f);
  // spatial_scale: input px (0, 0, 6, 4) at 1/2 is the first example.
  out = RoiAlign(Map2x3(), {{{0, 0, 6, 4}}}, 0.5, 1, 1);
  EXPECT_FLOAT_EQ(out.item<float>(), 2.5f);
  // No RoIs at all.
  EXPECT_EQ(RoiAlign(Map2x3(), {{}}, 1.0, 7, 2).size(0), 0);
}

// The definition, pixel by pixel: out[r, c, p, q] = mean over the s x s samples of cell (p, q) of
// the bilinear interpolation of channel c at the sample, coordinates clamped to the map; the
// gradient of sum(out * weights) scatters each sample's bilinear weights back.
struct Reference {
  std::vector<float> out, grad;
};

Reference BruteForce(const std::vector<float>& f, int n, int c, int h, int w,
                     const std::vector<std::vector<Box2D>>& rois, double scale, int p, int s,
                     const std::vector<float>& weights) {
  Reference ref;
  ref.grad.assign(f.size(), 0.0f);
  int r_index = 0;
  for (int b = 0; b < n; ++b) {
    for (const Box2D& box : rois[b]) {
      for (int ch = 0; ch < c; ++ch) {
        for (int py = 0; py < p; ++py) {
          for (int px = 0; px < p; ++px) {
            double sum = 0;
            const size_t out_index = ((static_cast<size_t>(r_index) * c + ch) * p + py) * p + px;
            for (int sy = 0; sy < s; ++sy) {
              for (int sx = 0; sx < s; ++sx) {
                const double bin_h = box.Height() * scale / p, bin_w = box.Width() * scale / p;
                double y = box.top * scale - 0.5 + bin_h * (py + (sy + 0.5) / s);
                double x = box.left * scale - 0.5 + bin_w * (px + (sx + 0.5) / s);
                y = std::clamp(y, 0.0, h - 1.0);
                x = std::clamp(x, 0.0, w - 1.0);
                const int y0 = static_cast<int>(std::floor(y)),
                          x0 = static_cast<int>(std::floor(x));
                const int y1 = std::min(y0 + 1, h - 1), x1 = std::min(x0 + 1, w - 1);
                const double ly = y - y0, lx = x - x0;
                const std::array<std::tuple<int, int, double>, 4> taps = {
                    std::tuple{y0, x0, (1 - ly) * (1 - lx)}, std::tuple{y0, x1, (1 - ly) * lx},
                    std::tuple{y1, x0, ly * (1 - lx)}, std::tuple{y1, x1, ly * lx}};
                for (const auto& [yy, xx, wt] : taps) {
                  const size_t fi = ((static_cast<size_t>(b) * c + ch) * h + yy) * w + xx;
                  sum += wt * f[fi];
                  ref.grad[fi] += static_cast<float>(wt / (s * s) * weights[out_index]);
                }
              }
            }
            if (ref.out.size() <= out_index) ref.out.resize(out_index + 1);
            ref.out[out_index] = static_cast<float>(sum / (s * s));
          }
        }
      }
      ++r_index;
    }
  }
  return ref;
}

TEST(RpnRoiAlignTest, MatchesBruteForceValuesAndGradients) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-6, 30), size(1, 20);
  const int n = 2, c = 3, h = 5, w = 7, p = 3, s = 2;
  const double scale = 0.25;  // input px are 4 x finer than the map
  std::vector<std::vector<Box2D>> rois(n);
  for (int b = 0; b < n; ++b) {
    for (int k = 0; k < 2 + b; ++k) {
      const double x = coord(rng), y = coord(rng);
      rois[b].push_back({x, y, x + size(rng), y + size(rng)});
    }
  }
  torch::manual_seed(1);
  torch::Tensor features = torch::randn({n, c, h, w}).requires_grad_(true);
  const torch::Tensor out = RoiAlign(features, rois, scale, p, s);
  ASSERT_EQ(out.sizes(), (torch::IntArrayRef{5, c, p, p}));
  const torch::Tensor weights = torch::randn(out.sizes());
  (out * weights).sum().backward();
  const torch::Tensor fc = features.detach().contiguous();
  const std::vector<float> f(fc.data_ptr<float>(), fc.data_ptr<float>() + fc.numel());
  const torch::Tensor wc = weights.contiguous();
  const std::vector<float> wv(wc.data_ptr<float>(), wc.data_ptr<float>() + wc.numel());
  const Reference ref = BruteForce(f, n, c, h, w, rois, scale, p, s, wv);
  const torch::Tensor oc = out.detach().contiguous();
  ASSERT_EQ(static_cast<size_t>(oc.numel()), ref.out.size());
  for (size_t i = 0; i < ref.out.size(); ++i) {
    EXPECT_NEAR(oc.data_ptr<float>()[i], ref.out[i], 1e-5) << i;
  }
  const torch::Tensor g = features.grad().contiguous();
  for (size_t i = 0; i < ref.grad.size(); ++i) {
    EXPECT_NEAR(g.data_ptr<float>()[i], ref.grad[i], 1e-5) << i;
  }
}

TEST(RpnRoiAlignTest, BackwardIsDeterministic) {
  torch::set_num_threads(2);
  std::vector<std::vector<Box2D>> rois(2);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 100);
  for (auto& image : rois) {
    for (int k = 0; k < 64; ++k) {
      const double x = u(rng), y = u(rng);
      image.push_back({x, y, x + 10 + u(rng) / 4, y + 10 + u(rng) / 4});
    }
  }
  torch::manual_seed(2);
  const torch::Tensor base = torch::randn({2, 16, 12, 12});
  const torch::Tensor weights = torch::randn({128, 16, 7, 7});
  auto gradient = [&] {
    torch::Tensor f = base.clone().requires_grad_(true);
    (RoiAlign(f, rois, 1.0 / 16, 7, 2) * weights).sum().backward();
    return f.grad().clone();
  };
  const torch::Tensor a = gradient(), b = gradient();
  EXPECT_TRUE(torch::equal(a, b));
}

TEST(RpnNetTest, OutputLayoutAndBranchParameterCounts) {
  torch::manual_seed(1);
  RpnNet rgb(TinyRpnConfig(RpnInput::kRgb)), rgbd(TinyRpnConfig(RpnInput::kRgbd));
  rgb->eval();
  const torch::Tensor features = rgb->Features(torch::rand({2, 3, 32, 64}));
  ASSERT_EQ(features.sizes(), (torch::IntArrayRef{2, 16, 2, 4}));
  const auto [objectness, deltas] = rgb->Rpn(features);
  EXPECT_EQ(objectness.sizes(), (torch::IntArrayRef{2, 2 * 4 * 6}));
  EXPECT_EQ(deltas.sizes(), (torch::IntArrayRef{2, 2 * 4 * 6, 4}));
  // The objectness of anchor (row 1, column 2, anchor 5) is channel 5 of cell (1, 2).
  const torch::Tensor h = torch::relu(rgb->rpn_conv(features));
  const torch::Tensor raw = rgb->rpn_objectness(h);
  EXPECT_FLOAT_EQ(objectness[1][(1 * 4 + 2) * 6 + 5].item<float>(), raw[1][5][1][2].item<float>());
  const torch::Tensor raw_deltas = rgb->rpn_deltas(h);
  EXPECT_FLOAT_EQ(deltas[1][(1 * 4 + 2) * 6 + 5][3].item<float>(),
                  raw_deltas[1][5 * 4 + 3][1][2].item<float>());
  auto count = [](torch::nn::Module& m) {
    int64_t k = 0;
    for (const auto& p : m.parameters()) k += p.numel();
    return k;
  };
  // Same widths: the geometry branch is the image branch's twin; the rest differs by the fusion.
  EXPECT_EQ(count(*rgbd->geometry), count(*rgbd->image));
  EXPECT_EQ(count(*rgbd->image), count(*rgb->image));
  EXPECT_EQ(count(*rgbd) - count(*rgb), count(*rgbd->geometry) + count(*rgbd->fuse));
  EXPECT_EQ(count(*rgbd->fuse), (16 + 16) * 16 + 16);
}

TEST(RpnNetTest, FeatureStride8KeepsTheSecondStagesResolution) {
  RpnConfig config = TinyRpnConfig(RpnInput::kRgbd);
  config.feature_stride = 8;
  config.anchors.stride_px = 8;
  RpnNet net(config), coarse(TinyRpnConfig(RpnInput::kRgbd));
  net->eval();
  const torch::Tensor features = net->Features(torch::rand({1, 6, 32, 64}));
  EXPECT_EQ(features.sizes(), (torch::IntArrayRef{1, 16, 4, 8}));
  EXPECT_EQ(net->Rpn(features).first.size(1), 4 * 8 * 6);
  int64_t a = 0, b = 0;  // the same weights' shapes: only a stride changes
  for (const auto& p : net->parameters()) a += p.numel();
  for (const auto& p : coarse->parameters()) b += p.numel();
  EXPECT_EQ(a, b);
  const RpnModel model(config, 1);
  EXPECT_EQ(model.anchors().size(), 4u * 8u * 6u);
  EXPECT_NEAR(model.anchors()[6].left + model.anchors()[6].right, 2 * 12.0, 1e-9);  // cell 1: x 12
  config.anchors.stride_px = 16;
  EXPECT_THROW(config.Check(), std::invalid_argument);
}

TEST(RpnNetTest, MirroredRgbdModelStartsAsTheRgbModel) {
  // Train-free: a random RGB model, mirrored into an RGB-D model, detects the same boxes whatever
  // the geometry channels hold (the fusion starts as [identity | 0]).
  const RpnModel rgb(TinyRpnConfig(RpnInput::kRgb), 3);
  RpnModel rgbd(TinyRpnConfig(RpnInput::kRgbd), 4);
  EXPECT_GT(rgbd.InitFrom(rgb, /*geometry_too=*/true), 0);
  std::mt19937 rng(1);
  PlanarImage colour{3, 32, 64, std::vector<float>(3 * 32 * 64)};
  PlanarImage both{6, 32, 64, std::vector<float>(6 * 32 * 64)};
  std::uniform_real_distribution<float> u(0, 1);
  for (float& v : colour.data) v = u(rng);
  std::copy(colour.data.begin(), colour.data.end(), both.data.begin());
  for (size_t i = colour.data.size(); i < both.data.size(); ++i) both.data[i] = u(rng);
  RpnDetectOptions options;
  options.decode.score_threshold = 0.0f;
  const auto a = rgb.Detect({colour}, options), b = rgbd.Detect({both}, options);
  ASSERT_EQ(a[0].size(), b[0].size());
  ASSERT_FALSE(a[0].empty());
  for (size_t i = 0; i < a[0].size(); ++i) {
    EXPECT_NEAR(a[0][i].score, b[0][i].score, 1e-5);
    EXPECT_NEAR(a[0][i].box.left, b[0][i].box.left, 1e-3);
    EXPECT_GE(a[0][i].score, 0.0f);
    EXPECT_LE(a[0][i].score, 1.0f);
  }
  // Another image width cannot be mirrored.
  RpnConfig wide = TinyRpnConfig(RpnInput::kRgbd);
  wide.image_width = 8;
  RpnModel other(wide, 1);
  EXPECT_THROW(other.InitFrom(rgb), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet::internal
