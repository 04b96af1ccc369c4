// The 3D detector's torch-free parts: hand-computed pillars, anchors, box coding, auxiliary
// targets, PSWarp sampling points; rotated NMS against its defining properties on random boxes;
// the camera/velodyne box conversions; augmentation invariants; the config's JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stereodet/geometry/calibration.h"
#include "stereodet/geometry/iou.h"
#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/det3d/det3d_data.h"
#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/det3d/det3d_targets.h"
#include "stereodet/models/device.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

BevGridOptions SmallGrid() {
  BevGridOptions g;
  g.min_x_m = 0.0;
  g.max_x_m = 3.2;
  g.min_y_m = -1.6;
  g.max_y_m = 1.6;
  g.pillar_m = 0.4;
  return g;
}

TEST(Det3dPillarsTest, HandComputedCellsAndDecoration) {
  const std::vector<VeloPoint> points = {
      {0.1f, -1.5f, 0.0f, 0.5f},  // row 0, col 0
      {0.3f, -1.3f, 0.2f, 1.0f},  // row 0, col 0
      {1.0f, 0.5f, 0.0f, 0.0f},   // row 2 (1.0 / 0.4), col 5 (2.1 / 0.4)
      {5.0f, 0.0f, 0.0f, 0.0f},   // beyond x
      {1.0f, 0.0f, 2.0f, 0.0f},   // above z
      {NAN, 0.0f, 0.0f, 0.0f},    // not finite
  };
  const Pillars p = Pillarize(points, SmallGrid());
  ASSERT_EQ(p.cell.size(), 3u);
  EXPECT_EQ(p.cell[0], 0);
  EXPECT_EQ(p.cell[1], 0);
  EXPECT_EQ(p.cell[2], 2 * 8 + 5);
  EXPECT_EQ(p.num_pillars, 2);
  // Point 0: pillar mean (0.2, -1.4, 0.1), cell centre (0.2, -1.4).
  const float expected0[kPillarFeatures] = {0.1f,  -1.5f, 0.0f,  0.5f, -0.1f,
                                            -0.1f, -0.1f, -0.1f, -0.1f};
  for (int k = 0; k < kPillarFeatures; ++k) {
    EXPECT_NEAR(p.features[k], expected0[k], 1e-6) << "feature " << k;
  }
  // Point 2 alone in its pillar: mean offsets 0; cell centre (1.0, 0.6).
  EXPECT_NEAR(p.features[2 * kPillarFeatures + 4], 0.0, 1e-6);
  EXPECT_NEAR(p.features[2 * kPillarFeatures + 7], 0.0, 1e-6);
  EXPECT_NEAR(p.features[2 * kPillarFeatures + 8], -0.1, 1e-6);
  EXPECT_FLOAT_EQ(p.xyz[2 * 3 + 1], 0.5f);
}

TEST(Det3dPillarsTest, GridChecksItsShape) {
  BevGridOptions g = SmallGrid();
  g.max_x_m = 3.0;  // 7.5 pillars
  EXPECT_THROW(g.Check(), std::invalid_argument);
  g.max_x_m = 2.8;  // 7 pillars, not a multiple of 8
  EXPECT_THROW(g.Check(), std::invalid_argument);
}

BevGridOptions CarGrid() {
  BevGridOptions g;
  g.min_x_m = 0.0;
  g.max_x_m = 12.8;
  g.min_y_m = -6.4;
  g.max_y_m = 6.4;
  g.pillar_m = 0.4;
  return g;
}

TEST(Det3dAnchorsTest, LayoutAndHandComputedAssignment) {
  const std::vector<AnchorClass> classes = {DefaultAnchorClass("Car")};
  const std::vector<LidarBox> anchors = GenerateAnchors(CarGrid(), 2, classes);
  ASSERT_EQ(anchors.size(), 16u * 16u * 2u);
  // Cell (row 5, col 7) at 0.8 m a cell: centre (4.4, -0.4); index (5 * 16 + 7) * 2 + rotation.
  const size_t at = (5 * 16 + 7) * 2;
  EXPECT_NEAR(anchors[at].x, 4.4, 1e-9);
  EXPECT_NEAR(anchors[at].y, -0.4, 1e-9);
  EXPECT_NEAR(anchors[at].yaw, 0.0, 1e-12);
  EXPECT_NEAR(anchors[at + 1].yaw, M_PI / 2, 1e-12);
  std::vector<int> anchor_class(anchors.size(), 0);
  LidarBox box = anchors[at];
  box.label = 0;
  const AnchorTargets t = AssignAnchors(anchors, anchor_class, classes, {box});
  // IoU 1 with itself; 0.66 with the anchors 0.8 m ahead and behind (3.1 x 1.6 overlap:
  // 4.96 / 7.52); 0.33 beside (3.12 / 9.36), 0.42 at 1.6 m (3.68 / 8.8), 0.26 rotated 90
  // degrees (2.56 / 9.92): negatives.
  EXPECT_EQ(t.num_positive, 3);
  EXPECT_EQ(t.labels[at], 1);
  EXPECT_EQ(t.labels[at + 2 * 16], 1);
  EXPECT_EQ(t.labels[at - 2 * 16], 1);
  EXPECT_EQ(t.labels[at + 1], 0);
  EXPECT_EQ(t.labels[at + 2], 0);
  EXPECT_EQ(t.labels[at + 4 * 16], 0);
  for (int k = 0; k < kBoxCodeSize; ++k) EXPECT_FLOAT_EQ(t.box_codes[at * kBoxCodeSize + k], 0.0f);
  // Ahead by one cell: dx = -0.8 / hypot(3.9, 1.6).
  EXPECT_NEAR(t.box_codes[(at + 2 * 16) * kBoxCodeSize], -0.8 / std::hypot(3.9, 1.6), 1e-6);
  EXPECT_LT(LidarBevIou(anchors[at], anchors[at + 2 * 16]), 0.66);
  EXPECT_GT(LidarBevIou(anchors[at], anchors[at + 2 * 16]), 0.65);
}

TEST(Det3dAnchorsTest, SmallBoxGetsItsBestAnchorAndIgnoresBetweenThresholds) {
  const std::vector<AnchorClass> classes = {DefaultAnchorClass("Car")};
  const std::vector<LidarBox> anchors = GenerateAnchors(CarGrid(), 2, classes);
  std::vector<int> anchor_class(anchors.size(), 0);
  // A 3.4 x 1 m box: IoU with the 3.9 x 1.6 anchor at its centre is 3.4 / 6.24 = 0.54 < 0.6, with
  // those 0.8 m ahead and behind 2.85 / 6.79 = 0.42.
  LidarBox box{.x = 4.4, .y = -0.4, .z = -1.0, .l = 3.4, .w = 1.0, .h = 1.5, .yaw = 0, .label = 0};
  const AnchorTargets t = AssignAnchors(anchors, anchor_class, classes, {box});
  EXPECT_EQ(t.num_positive, 1);
  EXPECT_EQ(t.labels[(5 * 16 + 7) * 2], 1);
  // A class the anchors do not have is skipped.
  box.label = 3;
  EXPECT_EQ(AssignAnchors(anchors, anchor_class, classes, {box}).num_positive, 0);
  // Between the thresholds (0.45 <= IoU < 0.6): ignored. Shifted 1.2 m: 2.7 x 1.6 / (12.48 - 4.32)
  // = 0.53 with the anchor at (4.4, -0.4).
  LidarBox car{.x = 5.6, .y = -0.4, .z = -1.0, .l = 3.9, .w = 1.6, .h = 1.56, .yaw = 0, .label = 0};
  const AnchorTargets u = AssignAnchors(anchors, anchor_class, classes, {car});
  EXPECT_EQ(u.labels[(5 * 16 + 7) * 2], kIgnoreAnchor);
}

TEST(Det3dBoxCodingTest, RoundTripAndDirection) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const LidarBox anchor{.x = 10 + 5 * u(rng),
                          .y = 5 * u(rng),
                          .z = -1,
                          .l = 3.9,
                          .w = 1.6,
                          .h = 1.56,
                          .yaw = (i % 2) * M_PI / 2,
                          .label = 0};
    const LidarBox box{.x = anchor.x + u(rng),
                       .y = anchor.y + u(rng),
                       .z = -1 + 0.3 * u(rng),
                       .l = 4 + 0.5 * u(rng),
                       .w = 1.7 + 0.2 * u(rng),
                       .h = 1.5 + 0.2 * u(rng),
                       .yaw = M_PI * u(rng),
                       .label = 0};
    const LidarBox back = DecodeBox(EncodeBox(box, anchor), anchor);
    EXPECT_NEAR(back.x, box.x, 1e-5);
    EXPECT_NEAR(back.y, box.y, 1e-5);
    EXPECT_NEAR(back.z, box.z, 1e-5);
    EXPECT_NEAR(back.l, box.l, 1e-5);
    EXPECT_NEAR(back.w, box.w, 1e-5);
    EXPECT_NEAR(back.h, box.h, 1e-5);
    EXPECT_NEAR(back.yaw, box.yaw, 1e-5);
    // The regression may come back a half turn off; the direction bin puts it right.
    const double flipped = back.yaw + M_PI;
    EXPECT_NEAR(std::abs(WrapAngle(ApplyDirection(flipped, DirectionBin(box.yaw)) - box.yaw)), 0.0,
                1e-5);
  }
  EXPECT_EQ(DirectionBin(0.1), 0);
  EXPECT_EQ(DirectionBin(-0.1), 1);
  EXPECT_EQ(DirectionBin(3.0), 0);
  EXPECT_EQ(DirectionBin(3.2), 1);
  const LidarBox a{.x = 1, .y = 2, .z = -1, .l = 3, .w = 4, .h = 2, .yaw = 0, .label = 0};
  LidarBox b = a;
  b.x += 5;  // hypot(3, 4) = 5
  b.h = 2 * std::exp(1.0);
  const std::array<float, kBoxCodeSize> code = EncodeBox(b, a);
  EXPECT_FLOAT_EQ(code[0], 1.0f);
  EXPECT_FLOAT_EQ(code[5], 1.0f);
}

TEST(Det3dAuxiliaryTargetsTest, PointsInARotatedBoxAndCentreOffsets) {
  // 4 m long along y (yaw 90 degrees), 2 m wide along x, 1.5 m high.
  const LidarBox box{
      .x = 10, .y = 0, .z = -1, .l = 4, .w = 2, .h = 1.5, .yaw = M_PI / 2, .label = 0};
  const std::vector<float> xyz = {
      10.0f, 1.9f, -1.0f,  // inside: 1.9 < 2 along the length
      10.9f, 0.0f, -0.5f,  // inside: 0.9 < 1 across
      11.5f, 0.0f, -1.0f,  // outside (inside were the box not rotated)
      10.0f, 0.0f, 0.0f,   // above (z 1 > 0.75 from the centre)
  };
  const PointTargets t = AuxiliaryTargets(xyz, {box});
  EXPECT_EQ(t.num_foreground, 2);
  EXPECT_EQ(t.foreground, (std::vector<float>{1, 1, 0, 0}));
  EXPECT_NEAR(t.offsets[0], 0.0, 1e-6);
  EXPECT_NEAR(t.offsets[1], -1.9, 1e-6);
  EXPECT_NEAR(t.offsets[2], 0.0, 1e-6);
  EXPECT_NEAR(t.offsets[3], -0.9, 1e-6);
  EXPECT_NEAR(t.offsets[5], -0.5, 1e-6);
  for (int k = 6; k < 12; ++k) EXPECT_EQ(t.offsets[k], 0.0f);
}

TEST(Det3dPartWarpTest, HandComputedSamplingPoints) {
  const LidarBox box{.x = 2, .y = 3, .z = 0, .l = 4, .w = 2, .h = 1, .yaw = M_PI / 2, .label = 0};
  const std::vector<std::array<double, 2>> p = PartSamplingPoints(box, 2, 2);
  ASSERT_EQ(p.size(), 4u);
  // Part (i, j) at (u, v) = (-1 or 1, -0.5 or 0.5) in the box frame; rotated 90 degrees:
  // (x, y) = (2 - v, 3 + u).
  const double expected[4][2] = {{2.5, 2}, {1.5, 2}, {2.5, 4}, {1.5, 4}};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(p[k][0], expected[k][0], 1e-12) << k;
    EXPECT_NEAR(p[k][1], expected[k][1], 1e-12) << k;
  }
  const BevGridOptions g;  // x 0..48, y -24..24
  EXPECT_NEAR(NormalizedBevCoordinates(24, 0, g)[0], 0.0, 1e-12);
  EXPECT_NEAR(NormalizedBevCoordinates(24, 0, g)[1], 0.0, 1e-12);
  EXPECT_NEAR(NormalizedBevCoordinates(0, -24, g)[0], -1.0, 1e-12);
  EXPECT_NEAR(NormalizedBevCoordinates(48, 12, g)[0], 0.5, 1e-12);
  EXPECT_NEAR(NormalizedBevCoordinates(48, 12, g)[1], 1.0, 1e-12);
}

TEST(Det3dBoxesTest, BevIouOfRotatedBoxes) {
  const LidarBox a{.x = 5, .y = 1, .z = 0, .l = 4, .w = 2, .h = 1, .yaw = 0, .label = 0};
  LidarBox b = a;
  b.yaw = M_PI / 2;  // a cross: 2 x 2 in common, union 12
  EXPECT_NEAR(LidarBevIou(a, b), 4.0 / 12.0, 1e-9);
  b = a;
  b.x += 2;  // half the length: 4 / 12
  EXPECT_NEAR(LidarBevIou(a, b), 4.0 / 12.0, 1e-9);
  b.yaw = M_PI;  // the same footprint turned around
  EXPECT_NEAR(LidarBevIou(a, b), 4.0 / 12.0, 1e-9);
  b.x = 20;
  EXPECT_EQ(LidarBevIou(a, b), 0.0);
  // The corners of the proxy are those of the box.
  const auto corners = LidarBevCorners(b);
  // Turned around (yaw pi): front-left is (x - l/2, y - w/2).
  EXPECT_NEAR(corners[0].x(), 18, 1e-9);
  EXPECT_NEAR(corners[0].y(), 0, 1e-9);
}

TEST(Det3dBoxesTest, RotatedNmsAgainstItsDefinitionOnRandomBoxes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 30; ++trial) {
    std::vector<ScoredLidarBox> boxes;
    for (int i = 0; i < 40; ++i) {
      ScoredLidarBox b;
      b.box = {.x = 10 * u(rng),
               .y = 10 * u(rng),
               .z = 0,
               .l = 1 + 3 * u(rng),
               .w = 1 + 1.5 * u(rng),
               .h = 1.5,
               .yaw = 2 * M_PI * u(rng),
               .label = static_cast<int>(u(rng) * 2)};
      b.score = static_cast<float>(u(rng));
      boxes.push_back(b);
    }
    RotatedNmsOptions options;
    options.iou_threshold = 0.2;
    options.max_candidates = 0;
    options.max_detections = 0;
    const std::vector<ScoredLidarBox> kept = RotatedNms(boxes, options);
    // Brute force: greedy NMS's result is the unique set in which (1) no kept pair of a label
    // overlaps by more than the threshold and (2) every dropped box overlaps a higher-scored kept
    // box of its label by more than it.
    auto is_kept = [&](const ScoredLidarBox& b) {
      for (const ScoredLidarBox& k : kept) {
        if (k.box == b.box && k.score == b.score) return true;
      }
      return false;
    };
    for (size_t i = 0; i < kept.size(); ++i) {
      if (i > 0) {
        EXPECT_GE(kept[i - 1].score, kept[i].score);
      }
      for (size_t j = i + 1; j < kept.size(); ++j) {
        if (kept[i].box.label != kept[j].box.label) continue;
        EXPECT_LE(BevIou(BevProxy(kept[i].box), BevProxy(kept[j].box)), 0.2);
      }
    }
    for (const ScoredLidarBox& b : boxes) {
      if (is_kept(b)) continue;
      bool covered = false;
      for (const ScoredLidarBox& k : kept) {
        covered |= k.box.label == b.box.label && k.score >= b.score &&
                   BevIou(BevProxy(k.box), BevProxy(b.box)) > 0.2;
      }
      EXPECT_TRUE(covered) << "trial " << trial;
    }
  }
}

TEST(Det3dBoxesTest, NmsKeepsAtMostMaxDetections) {
  std::vector<ScoredLidarBox> boxes;
  for (int i = 0; i < 300; ++i) {
    boxes.push_back(
        {{.x = 3.0 * i, .y = 0, .z = 0, .l = 1, .w = 1, .h = 1, .yaw = 0, .label = 0}, 0.5f});
  }
  EXPECT_EQ(RotatedNms(boxes, {}).size(), 100u);
  boxes.push_back(boxes[0]);  // a duplicate is suppressed
  RotatedNmsOptions all;
  all.max_candidates = 0;
  all.max_detections = 0;
  EXPECT_EQ(RotatedNms(boxes, all).size(), 300u);
}

TEST(Det3dBoxesTest, CameraFrameRoundTripAndKittiDetection) {
  const Calibration calib = KittiLikeCalibration();
  Object label;
  label.type = "Car";
  label.box3d.h = 1.5;
  label.box3d.w = 1.6;
  label.box3d.l = 3.9;
  label.box3d.location = {1.0, 1.7, 15.0};
  label.box3d.rotation_y = 0.3;
  const LidarBox box = LidarBoxFromObject(label, calib);
  // KITTI's velodyne sits behind and above the camera: x ~ z_cam, y ~ -x_cam.
  EXPECT_NEAR(box.x, 15.0, 0.5);
  EXPECT_NEAR(box.y, -1.0, 0.5);
  EXPECT_NEAR(WrapAngle(box.yaw + 0.3 + M_PI / 2), 0.0, 0.05);
  const Box3D back = Box3DFromLidarBox(box, calib);
  EXPECT_NEAR((back.location - label.box3d.location).norm(), 0.0, 1e-9);
  // The heading goes through the velodyne frame's small tilt and back into the ground plane.
  EXPECT_NEAR(WrapAngle(back.rotation_y - 0.3), 0.0, 1e-3);
  EXPECT_NEAR(LidarBevIou(box, box), 1.0, 1e-9);

  ScoredLidarBox scored{box, 0.75f};
  scored.box.label = 0;
  const std::optional<Object> o = ToKitti3DDetection(scored, {"Car"}, calib, 1242, 375);
  ASSERT_TRUE(o.has_value());
  EXPECT_EQ(o->type, "Car");
  EXPECT_EQ(*o->score, 0.75);
  EXPECT_NEAR(o->box3d.location.z(), 15.0, 1e-3);
  EXPECT_NEAR(o->alpha, WrapAngle(0.3 - std::atan2(1.0, 15.0)), 1e-3);
  EXPECT_GT(o->box.Width(), 0);
  EXPECT_LE(o->box.right, 1242);
  // Projection of the centre lies inside the 2D box.
  const Eigen::Vector2d centre = calib.ProjectRectToImage(label.box3d.Centre());
  EXPECT_GT(centre.x(), o->box.left);
  EXPECT_LT(centre.x(), o->box.right);
  // Behind the camera: no detection.
  scored.box.x = -10;
  EXPECT_FALSE(ToKitti3DDetection(scored, {"Car"}, calib, 1242, 375).has_value());
}

TEST(Det3dAugmentTest, ObjectsKeepTheirPointsAndNeverCollide) {
  Det3dFrame frame;
  frame.boxes = {
      {.x = 10, .y = 0, .z = -1, .l = 3.9, .w = 1.6, .h = 1.5, .yaw = 0, .label = 0},
      {.x = 14.2, .y = 0.3, .z = -1, .l = 3.9, .w = 1.6, .h = 1.5, .yaw = 0.1, .label = 0},
      {.x = 12, .y = 5, .z = -1, .l = 3.9, .w = 1.6, .h = 1.5, .yaw = 1.2, .label = 0}};
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-0.45f, 0.45f);
  for (const LidarBox& b : frame.boxes) {
    for (int i = 0; i < 50; ++i) {
      const double along = u(rng) * b.l, across = u(rng) * b.w;
      frame.points.push_back(
          {static_cast<float>(b.x + std::cos(b.yaw) * along - std::sin(b.yaw) * across),
           static_cast<float>(b.y + std::sin(b.yaw) * along + std::cos(b.yaw) * across),
           static_cast<float>(b.z + u(rng) * b.h), 0.5f});
    }
  }
  Det3dAugmentOptions options;
  options.object_translation_sigma_m = 1.0;  // often collides: exercises the test
  int moved = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const Det3dFrame out = AugmentFrame(frame, options, seed);
    ASSERT_EQ(out.boxes.size(), 3u);
    ASSERT_EQ(out.points.size(), frame.points.size());
    for (size_t b = 0; b < 3; ++b) {
      int inside = 0;
      for (const VeloPoint& p : out.points) inside += PointInBox(out.boxes[b], p.x, p.y, p.z);
      EXPECT_EQ(inside, 50) << "seed " << seed << " box " << b;
      for (size_t o = b + 1; o < 3; ++o) {
        EXPECT_EQ(LidarBevIou(out.boxes[b], out.boxes[o]), 0.0) << "seed " << seed;
      }
    }
    moved += out.boxes[0].x != frame.boxes[0].x;
    // The same seed gives the same frame.
    EXPECT_EQ(AugmentFrame(frame, options, seed).boxes, out.boxes);
  }
  EXPECT_GT(moved, 0);
  // Flip alone mirrors y and the heading.
  Det3dAugmentOptions flip;
  flip.global_rotation_rad = 0;
  flip.global_scale_min = flip.global_scale_max = 1;
  flip.object_translation_sigma_m = 0;
  flip.object_rotation_rad = 0;
  int flipped = 0;
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const Det3dFrame out = AugmentFrame(frame, flip, seed);
    if (out.boxes[2].y < 0) {
      ++flipped;
      EXPECT_NEAR(out.boxes[2].y, -5, 1e-9);
      EXPECT_NEAR(out.boxes[2].yaw, -1.2, 1e-9);
      EXPECT_FLOAT_EQ(out.points[0].y, -frame.points[0].y);
    }
  }
  EXPECT_GT(flipped, 0);
  EXPECT_LT(flipped, 10);
}

TEST(Det3dConfigTest, JsonRoundTripAndErrorsNameTheField) {
  Det3dConfig c;
  c.input = PointSource::kStereo;
  c.classes = {"Car", "Pedestrian"};
  c.base_channels = 24;
  c.grid.pillar_m = 0.2;
  const Det3dConfig back = Det3dConfigFromJson(Det3dConfigToJson(c), "m.json");
  EXPECT_EQ(back.input, PointSource::kStereo);
  EXPECT_EQ(back.classes, c.classes);
  EXPECT_EQ(back.base_channels, 24);
  EXPECT_EQ(back.grid.pillar_m, 0.2);
  std::string text = Det3dConfigToJson(c);
  text.replace(text.find("\"stereo\""), 8, "\"radar\"");
  try {
    Det3dConfigFromJson(text, "m.json");
    FAIL() << "accepted input radar";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("m.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("input"), std::string::npos);
  }
}

TEST(DeviceTest, ParsesNamesAndRefusesAnUnavailableGpu) {
  EXPECT_EQ(ParseComputeDevice("cpu"), ComputeDevice::kCpu);
  EXPECT_EQ(ParseComputeDevice("cuda"), ComputeDevice::kCuda);
  EXPECT_FALSE(ParseComputeDevice("gpu").has_value());
  EXPECT_THROW(ResolveComputeDevice("tpu"), std::invalid_argument);
  EXPECT_EQ(ResolveComputeDevice("cpu"), ComputeDevice::kCpu);
  if (CudaAvailable()) {
    EXPECT_EQ(ResolveComputeDevice("cuda"), ComputeDevice::kCuda);
  } else {
    try {
      ResolveComputeDevice("cuda");
      FAIL() << "cuda accepted without a GPU";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("--device cpu"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace stereodet
