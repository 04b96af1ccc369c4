#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/eval/devkit_overlap_internal.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/test_objects.h"
#include "stereodet/kitti/label_io.h"

namespace stereodet {
namespace {

using testing_objects::Devkit;
using testing_objects::Footprint;
using testing_objects::Line;

TEST(DevkitOverlapTest, HandComputableCases) {
  const Box3D label = Footprint(3.0, 20.0, 3.9, 1.6, 0.0, 1.65, 2.0);
  // Axis-aligned, shifted by half its length: intersection 1.95 x 1.6 of union 5.85 x 1.6.
  Box3D det = label;
  det.location.x() += 1.95;
  EXPECT_NEAR(Devkit(OverlapKind::kBev, det, label), 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(Devkit(OverlapKind::kBev, det, label, DevkitCriterion::kDetectionSize), 0.5, 1e-6);
  // Same footprint, 0.5 m lower (y grows downwards): 1.5 of 2 m shared, 3D IoU 1.5 / 2.5.
  det = label;
  det.location.y() += 0.5;
  EXPECT_NEAR(Devkit(OverlapKind::kBev, det, label), 1.0, 1e-12);
  EXPECT_NEAR(Devkit(OverlapKind::k3D, det, label), 0.6, 1e-6);
  EXPECT_NEAR(Devkit(OverlapKind::k3D, det, label, DevkitCriterion::kDetectionSize), 0.75, 1e-6);
  // Apart: no intersection polygon, overlap 0 (the devkit's `in.empty() ? 0`).
  det = label;
  det.location.z() += 10.0;
  EXPECT_EQ(Devkit(OverlapKind::kBev, det, label), 0.0);
  EXPECT_EQ(Devkit(OverlapKind::k3D, det, label), 0.0);
}

TEST(DevkitOverlapTest, RejectsImageBoxes) {
  const Box3D b = Footprint(0, 10, 4, 2, 0);
  EXPECT_THROW(DevkitBoxOverlap(OverlapKind::k2D, DevkitCriterion::kUnion, b, b),
               std::invalid_argument);
}

// The band of KittiOverlapAtThreshold and PrepareClassFrame rests on this: away from the degenerate
// cases below, the devkit's (rescaled) arithmetic stays within a fraction of kDevkitTieBand of the
// exact overlap, so only values that close to tau, or to each other, can be decided otherwise.
TEST(DevkitOverlapTest, StaysWithinTheBandOfTheExactOverlapOnRandomBoxes) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const bool thin : {false, true}) {
    int overlapping = 0;
    double max_diff = 0.0;
    for (int i = 0; i < 3000; ++i) {
      Object label, det;
      label.box3d =
          Footprint(-10 + 20 * u(rng), 5 + 40 * u(rng), 0.5 + 4 * u(rng),
                    thin ? 0.01 + 0.09 * u(rng) : 0.5 + 2 * u(rng),
                    -std::numbers::pi + 2 * std::numbers::pi * u(rng), 1 + u(rng), 1 + u(rng));
      det.box3d = label.box3d;
      const double step = thin ? 0.02 : 1.0;
      det.box3d.location +=
          Eigen::Vector3d(step * (u(rng) - 0.5), 0.5 * (u(rng) - 0.5), step * (u(rng) - 0.5));
      det.box3d.w *= 0.8 + 0.4 * u(rng);
      det.box3d.l *= 0.8 + 0.4 * u(rng);
      det.box3d.rotation_y += 0.3 * (u(rng) - 0.5);
      if (KittiOverlap(OverlapKind::kBev, det, label) > 0) ++overlapping;
      for (const OverlapKind kind : {OverlapKind::kBev, OverlapKind::k3D}) {
        const double exact_union = KittiOverlap(kind, det, label);
        const double exact_own = KittiDontCareOverlap(kind, det, label);
        max_diff = std::max(max_diff, std::abs(Devkit(kind, det.box3d, label.box3d) - exact_union));
        max_diff = std::max(max_diff, std::abs(Devkit(kind, det.box3d, label.box3d,
                                                      DevkitCriterion::kDetectionSize) -
                                               exact_own));
      }
    }
    SCOPED_TRACE(thin ? "boxes 1-10 cm wide" : "KITTI-sized boxes");
    EXPECT_GT(overlapping, 2000);
    EXPECT_LT(max_diff, thin ? kDevkitTieBand / 4 : kDevkitTieBand / 20);
  }
}

// DevkitBoxOverlap keeps the last pairs' boost results per thread (BEV and 3D share the
// intersection). Whatever was asked before, and after the memory has been emptied, every pair's
// four overlaps come out the same: asked BEV first, 3D first, or with 70,000 other pairs between.
TEST(DevkitOverlapTest, SameValuesWhateverWasAskedBefore) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto random_pair = [&] {
    const Box3D label = Footprint(-10 + 20 * u(rng), 5 + 40 * u(rng), 0.5 + 4 * u(rng),
                                  0.5 + 2 * u(rng), u(rng) < 0.3 ? 1.57 : 6 * u(rng) - 3);
    Box3D det = label;
    det.location += Eigen::Vector3d(u(rng) - 0.5, 0.5 * (u(rng) - 0.5), u(rng) - 0.5);
    det.w *= 0.8 + 0.4 * u(rng);
    if (u(rng) < 0.5) det.rotation_y += 0.3 * (u(rng) - 0.5);
    return std::pair(det, label);
  };
  struct Four {
    std::optional<double> v[4];
  };
  auto four = [](const std::pair<Box3D, Box3D>& p, bool bev_first) {
    Four f;
    const OverlapKind kinds[2] = {bev_first ? OverlapKind::kBev : OverlapKind::k3D,
                                  bev_first ? OverlapKind::k3D : OverlapKind::kBev};
    for (int k = 0; k < 2; ++k) {
      const int slot = kinds[k] == OverlapKind::kBev ? 0 : 2;
      f.v[slot + 1] =
          DevkitBoxOverlap(kinds[k], DevkitCriterion::kDetectionSize, p.first, p.second);
      f.v[slot] = DevkitBoxOverlap(kinds[k], DevkitCriterion::kUnion, p.first, p.second);
    }
    return f;
  };
  std::vector<std::pair<Box3D, Box3D>> pairs;
  for (int i = 0; i < 300; ++i) pairs.push_back(random_pair());
  std::vector<Four> bev_first, three_d_first, after_flush;
  for (const auto& p : pairs) bev_first.push_back(four(p, true));
  for (int i = 0; i < 70000; ++i)
    DevkitBoxOverlap(OverlapKind::k3D, DevkitCriterion::kUnion, random_pair().first,
                     pairs[0].second);
  for (const auto& p : pairs) three_d_first.push_back(four(p, false));
  for (const auto& p : pairs) after_flush.push_back(four(p, true));
  for (size_t i = 0; i < pairs.size(); ++i) {
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(bev_first[i].v[k], three_d_first[i].v[k]) << "pair " << i << " value " << k;
      EXPECT_EQ(bev_first[i].v[k], after_flush[i].v[k]) << "pair " << i << " value " << k;
    }
  }
}

// Boost 1.74 loses the intersection of a footprint nested in a parallel one between common end
// lines (same centre, length and rotation, 6 cm wider): the devkit sees overlap 0, not 0.976, and
// KITTI mode follows it. Checked end to end against the devkit in evaluator_test.cc.
TEST(DevkitOverlapTest, LosesSomeNestedParallelFootprintsLikeTheDevkit) {
  const Object label = Line("Car 0.00 0 0.00 100 100 200 200 1.27 2.41 0.75 9.69 1.74 15.90 -1.57");
  const Object det =
      Line("Car -1 -1 0.00 100 100 200 200 1.27 2.47 0.75 9.69 1.74 15.90 -1.57 0.9");
  EXPECT_NEAR(KittiOverlap(OverlapKind::kBev, det, label), 2.41 / 2.47, 1e-12);
  EXPECT_EQ(Devkit(OverlapKind::kBev, det.box3d, label.box3d), 0.0);
  EXPECT_EQ(Devkit(OverlapKind::k3D, det.box3d, label.box3d), 0.0);
  EXPECT_EQ(KittiOverlapAtThreshold(OverlapKind::kBev, det, label, 0.7), 0.0);
  EXPECT_EQ(KittiOverlapAtThreshold(OverlapKind::k3D, det, label, 0.7), 0.0);
  // Identical footprints are exactly 1 in both arithmetics and keep the fast path.
  EXPECT_EQ(KittiOverlapAtThreshold(OverlapKind::kBev, label, label, 0.7), 1.0);
}

// A footprint with w = -1 and l > 0 is a reversed ring: boost returns no union and the devkit
// crashes (tools' repro D). The devkit has no answer; KittiOverlap's 0 stays.
TEST(DevkitOverlapTest, NoAnswerWhereTheDevkitCrashes) {
  const Object label =
      Line("Car 0.81 0 0.36 897.35 262.62 968.99 291.25 1.59 1.84 3.48 6.34 1.88 51.24 0.90");
  const Object det =
      Line("Car -1 -1 0.34 896.40 258.73 974.23 289.46 1.60 -1.00 3.61 6.34 1.85 51.24 1.00 0.56");
  EXPECT_FALSE(
      DevkitBoxOverlap(OverlapKind::kBev, DevkitCriterion::kUnion, det.box3d, label.box3d));
  EXPECT_FALSE(
      DevkitBoxOverlap(OverlapKind::kBev, DevkitCriterion::kDetectionSize, det.box3d, label.box3d));
  EXPECT_EQ(KittiOverlap(OverlapKind::kBev, det, label), 0.0);
  // Even with a threshold so low that 0 lies in the band, the value stays 0 (no crash, no NaN).
  EXPECT_EQ(KittiOverlapAtThreshold(OverlapKind::kBev, det, label, 1e-6), 0.0);
}

}  // namespace
}  // namespace stereodet
