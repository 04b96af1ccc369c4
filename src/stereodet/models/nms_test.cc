#include "stereodet/models/nms.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "stereodet/geometry/iou.h"

namespace stereodet {
namespace {

// The definition, written the slow way: over all boxes sorted by score (ties by index), a box is
// kept iff no kept box before it has the same label and IoU > threshold.
std::vector<ScoredBox> BruteForceNms(const std::vector<ScoredBox>& boxes, double iou_threshold) {
  std::vector<int> order(boxes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return boxes[a].score > boxes[b].score || (boxes[a].score == boxes[b].score && a < b);
  });
  std::vector<ScoredBox> kept;
  for (int i : order) {
    bool suppressed = false;
    for (const ScoredBox& k : kept) {
      if (k.label == boxes[i].label && Iou2D(k.box, boxes[i].box) > iou_threshold) {
        suppressed = true;
      }
    }
    if (!suppressed) kept.push_back(boxes[i]);
  }
  return kept;
}

TEST(NmsTest, HandCheckedCase) {
  // Two overlapping boxes of label 1 (IoU 0.6), one of label 2 on top of them, one far away.
  const std::vector<ScoredBox> boxes = {
      {{0, 0, 10, 10}, 0.9f, 1},
      {{0, 0, 10, 6}, 0.8f, 1},   // IoU with the first: 60 / 100 = 0.6 -> suppressed at 0.5
      {{0, 0, 10, 10}, 0.7f, 2},  // other label: kept
      {{50, 50, 60, 60}, 0.95f, 1},
  };
  NmsOptions options;
  options.iou_threshold = 0.5;
  const std::vector<ScoredBox> kept = NonMaximumSuppression(boxes, options);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0], boxes[3]);
  EXPECT_EQ(kept[1], boxes[0]);
  EXPECT_EQ(kept[2], boxes[2]);
  // At 0.6 the second box is not suppressed (strictly greater is required).
  options.iou_threshold = 0.6;
  EXPECT_EQ(NonMaximumSuppression(boxes, options).size(), 4u);
}

TEST(NmsTest, ThresholdsAndLimits) {
  const std::vector<ScoredBox> boxes = {{{0, 0, 10, 10}, 0.9f, 1},
                                        {{20, 0, 30, 10}, 0.5f, 1},
                                        {{40, 0, 50, 10}, 0.1f, 1},
                                        {{0, 0, 10, 10}, 0.6f, 2},
                                        {{20, 0, 30, 10}, 0.4f, 2}};
  NmsOptions options;
  options.score_threshold = 0.3f;
  EXPECT_EQ(NonMaximumSuppression(boxes, options).size(), 4u);
  options.max_candidates_per_label = 1;
  const auto top1 = NonMaximumSuppression(boxes, options);
  ASSERT_EQ(top1.size(), 2u);
  EXPECT_EQ(top1[0].score, 0.9f);
  EXPECT_EQ(top1[1].score, 0.6f);
  options.max_candidates_per_label = 0;
  options.max_detections = 3;
  const auto top3 = NonMaximumSuppression(boxes, options);
  ASSERT_EQ(top3.size(), 3u);
  EXPECT_EQ(top3[2].score, 0.5f);
}

TEST(NmsTest, MatchesBruteForceOnRandomBoxes) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> position(0.0, 100.0), size(2.0, 40.0);
  std::uniform_int_distribution<int> label(1, 3), coarse_score(0, 9);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<ScoredBox> boxes(1 + trial % 60);
    for (ScoredBox& b : boxes) {
      const double x = position(rng), y = position(rng);
      b.box = {x, y, x + size(rng), y + size(rng)};
      b.score = coarse_score(rng) / 10.0f;  // many ties on purpose
      b.label = label(rng);
    }
    const double threshold = (trial % 5) * 0.2 + 0.1;
    NmsOptions options;
    options.iou_threshold = threshold;
    EXPECT_EQ(NonMaximumSuppression(boxes, options), BruteForceNms(boxes, threshold))
        << "trial " << trial;
  }
}

}  // namespace
}  // namespace stereodet
