// The 3D detector's tensor pieces against hand-computed values and their torch-free references.
#include <gtest/gtest.h>

#include <random>

#include "stereodet/models/det3d/det3d_net_internal.h"

namespace stereodet {
namespace {

TEST(Det3dNetTest, PillarScatterTakesTheMaxPerPillar) {
  // Two frames of 8 x 8 cells; pillar 0 = frame 0 cell 5 (points A, B), pillar 1 = frame 1 cell 2
  // (point C); point D dropped (its pillar was full).
  const torch::Tensor features =
      torch::tensor({1.0f, 0.0f, 0.5f, 2.0f, 3.0f, 3.0f, 9.0f, 9.0f}).view({4, 2});
  const torch::Tensor slot = torch::tensor({int64_t{0}, int64_t{1}, int64_t{32}, int64_t{-1}});
  const torch::Tensor cell = torch::tensor({int64_t{5}, int64_t{64 + 2}});
  const torch::Tensor canvas = internal::ScatterPillars(features, slot, cell, 2, 32, 2, 8, 8);
  ASSERT_EQ(canvas.sizes(), (std::vector<int64_t>{2, 2, 8, 8}));
  EXPECT_FLOAT_EQ(canvas[0][0][0][5].item<float>(), 1.0f);
  EXPECT_FLOAT_EQ(canvas[0][1][0][5].item<float>(), 2.0f);
  EXPECT_FLOAT_EQ(canvas[1][0][0][2].item<float>(), 3.0f);
  EXPECT_FLOAT_EQ(canvas[1][1][0][2].item<float>(), 3.0f);
  EXPECT_FLOAT_EQ(canvas.sum().item<float>(), 9.0f);  // nothing else, D nowhere
}

TEST(Det3dNetTest, PartSamplingGridMatchesTheReference) {
  const BevGridOptions grid;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int parts_l = 3, parts_w = 2;
  std::vector<float> pu, pv;
  for (int i = 0; i < parts_l; ++i) {
    for (int j = 0; j < parts_w; ++j) {
      pu.push_back(static_cast<float>((i + 0.5) / parts_l - 0.5));
      pv.push_back(static_cast<float>((j + 0.5) / parts_w - 0.5));
    }
  }
  std::vector<LidarBox> boxes;
  std::vector<float> flat;
  for (int i = 0; i < 10; ++i) {
    const LidarBox b{.x = 48 * u(rng),
                     .y = 48 * u(rng) - 24,
                     .z = -1,
                     .l = 2 + 3 * u(rng),
                     .w = 1 + u(rng),
                     .h = 1.5,
                     .yaw = 6 * u(rng) - 3,
                     .label = 0};
    boxes.push_back(b);
    flat.insert(flat.end(), {float(b.x), float(b.y), float(b.z), float(b.l), float(b.w), float(b.h),
                             float(b.yaw)});
  }
  const torch::Tensor t = torch::tensor(flat).view({2, 5, 7});
  const torch::Tensor g = internal::PartSamplingGrid(t, torch::tensor(pu), torch::tensor(pv), grid);
  ASSERT_EQ(g.sizes(), (std::vector<int64_t>{2, 5, 6, 2}));
  for (int i = 0; i < 10; ++i) {
    const auto ref = PartSamplingPoints(boxes[i], parts_l, parts_w);
    for (int p = 0; p < 6; ++p) {
      const auto n = NormalizedBevCoordinates(ref[p][0], ref[p][1], grid);
      EXPECT_NEAR(g[i / 5][i % 5][p][0].item<float>(), n[0], 1e-5);
      EXPECT_NEAR(g[i / 5][i % 5][p][1].item<float>(), n[1], 1e-5);
    }
  }
}

}  // namespace
}  // namespace stereodet
