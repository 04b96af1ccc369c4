#include "stereodet/models/box_coder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "stereodet/geometry/iou.h"

namespace stereodet {
namespace {

TEST(BoxCoderTest, HandCheckedEncoding) {
  const DefaultBox prior{10, 20, 8, 4};
  const Box2D box{8, 19, 16, 23};  // centre (12, 21), size 8 x 4
  const std::array<float, 4> d = EncodeBox(box, prior);
  EXPECT_FLOAT_EQ(d[0], (12 - 10) / 8.0f / 0.1f);
  EXPECT_FLOAT_EQ(d[1], (21 - 20) / 4.0f / 0.1f);
  EXPECT_FLOAT_EQ(d[2], 0.0f);
  EXPECT_FLOAT_EQ(d[3], 0.0f);
}

TEST(BoxCoderTest, EncodeDecodeRoundTrip) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(0, 600), size(1, 300);
  for (int i = 0; i < 1000; ++i) {
    const double x = pos(rng), y = pos(rng);
    const Box2D box{x, y, x + size(rng), y + size(rng)};
    const DefaultBox prior{static_cast<float>(pos(rng)), static_cast<float>(pos(rng)),
                           static_cast<float>(size(rng)), static_cast<float>(size(rng))};
    const std::array<float, 4> d = EncodeBox(box, prior);
    const Box2D back = DecodeBox(d.data(), prior);
    EXPECT_NEAR(back.left, box.left, 1e-3 * (1 + std::abs(box.left)));
    EXPECT_NEAR(back.top, box.top, 1e-3 * (1 + std::abs(box.top)));
    EXPECT_NEAR(back.right, box.right, 1e-3 * (1 + std::abs(box.right)));
    EXPECT_NEAR(back.bottom, box.bottom, 1e-3 * (1 + std::abs(box.bottom)));
  }
}

TEST(BoxCoderTest, DecodeClampsHugeSizes) {
  const DefaultBox prior{0, 0, 1, 1};
  const float deltas[4] = {0, 0, 1e6f, 1e6f};
  const Box2D box = DecodeBox(deltas, prior);
  EXPECT_TRUE(std::isfinite(box.Width()));
  EXPECT_NEAR(box.Width(), 1000.0, 1e-6);
}

TEST(BoxCoderTest, MatchingPositivesForcedMatchesAndIgnores) {
  // Four default boxes in a row, 10 px apart.
  const std::vector<DefaultBox> priors = {
      {5, 5, 10, 10}, {15, 5, 10, 10}, {25, 5, 10, 10}, {45, 5, 10, 10}};
  const std::vector<TargetBox> objects = {
      {{0, 0, 10, 10}, 2},              // exactly prior 0
      {{12, 0, 22, 10}, 1},             // IoU 8/12 with prior 1: positive
      {{40, 0, 46, 10}, kIgnoreLabel},  // IoU 6/10 = 0.6 with prior 3 -> ignored
      {{100, 100, 101, 101}, 3},        // overlaps no prior: matches nothing (steals no prior)
  };
  const MatchResult m = MatchDefaultBoxes(priors, objects, {});
  ASSERT_EQ(m.labels.size(), 4u);
  EXPECT_EQ(m.labels[0], 2);
  EXPECT_EQ(m.labels[1], 1);
  EXPECT_EQ(m.labels[2], 0);  // IoU with object 1: 2/18 < 0.5 -> background
  EXPECT_EQ(m.labels[3], kIgnoreLabel);
  EXPECT_EQ(m.num_positive, 2);
  // The deltas of prior 1 decode to object 1.
  const Box2D decoded = DecodeBox(&m.deltas[4], priors[1]);
  EXPECT_NEAR(decoded.left, 12.0, 1e-4);
  EXPECT_NEAR(decoded.right, 22.0, 1e-4);
}

TEST(BoxCoderTest, EveryObjectGetsAPositive) {
  DefaultBoxOptions options;
  const std::vector<DefaultBox> priors = GenerateDefaultBoxes(options);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(0, 600), y(0, 170), w(4, 200), h(8, 150);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<TargetBox> objects;
    for (int i = 0; i < 6; ++i) {
      const double left = x(rng), top = y(rng);
      objects.push_back({{left, top, left + w(rng), top + h(rng)}, 1 + i % 3});
    }
    const MatchResult m = MatchDefaultBoxes(priors, objects, {});
    EXPECT_GE(m.num_positive, 1);
    // Each object's best prior decodes back to that object, or to one of the other objects if two
    // objects compete for it.
    for (const TargetBox& object : objects) {
      double best = -1;
      size_t best_j = 0;
      for (size_t j = 0; j < priors.size(); ++j) {
        const double iou = Iou2D(priors[j].ToBox2D(), object.box);
        if (iou > best) best = iou, best_j = j;
      }
      EXPECT_GE(m.labels[best_j], 1);
    }
  }
}

TEST(BoxCoderTest, DecodeDetectionsFindsTheConfidentBox) {
  const std::vector<DefaultBox> priors = {{5, 5, 10, 10}, {6, 5, 10, 10}, {50, 50, 10, 10}};
  const float deltas[12] = {};
  // 3 classes with background: prior 0 is class 1 (0.9), prior 1 duplicates it (0.8), prior 2
  // class 2.
  const float probabilities[9] = {0.1f, 0.9f, 0.0f, 0.2f, 0.8f, 0.0f, 0.3f, 0.0f, 0.7f};
  const std::vector<ScoredBox> d = DecodeDetections(deltas, probabilities, 3, priors, {});
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].label, 1);
  EXPECT_FLOAT_EQ(d[0].score, 0.9f);
  EXPECT_DOUBLE_EQ(d[0].box.left, 0.0);
  EXPECT_EQ(d[1].label, 2);
  EXPECT_DOUBLE_EQ(d[1].box.left, 45.0);
}

TEST(BoxCoderTest, ToKittiDetectionsScalesClipsAndMarks3DUnknown) {
  const std::vector<ScoredBox> boxes = {{{10, 5, 20, 15}, 0.9f, 2},
                                        {{-5, -5, 700, 200}, 0.5f, 1},
                                        {{700, 0, 800, 10}, 0.4f, 1}};  // fully outside
  const std::vector<Object> d =
      ToKittiDetections(boxes, {"Car", "Pedestrian"}, 2.0, 2.0, 1242, 375);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].type, "Pedestrian");
  EXPECT_EQ(d[0].box, (Box2D{20, 10, 40, 30}));
  EXPECT_NEAR(*d[0].score, 0.9, 1e-6);
  EXPECT_FALSE(d[0].Has3D());
  EXPECT_EQ(d[0].alpha, -10.0);
  EXPECT_EQ(d[1].box, (Box2D{0, 0, 1242, 375}));
  EXPECT_THROW(ToKittiDetections({{{0, 0, 1, 1}, 0.5f, 3}}, {"Car", "Pedestrian"}, 1, 1, 10, 10),
               std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
