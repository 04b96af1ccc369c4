#include "stereodet/eval/coco.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/eval/coco_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/fuzz_corpus.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

// A ground truth of one category (id 1) on the given images, from its annotations.
CocoGroundTruth OneCategory(std::vector<int64_t> image_ids,
                            std::vector<CocoAnnotation> annotations) {
  CocoGroundTruth gt;
  gt.source = "test";
  gt.image_ids = std::move(image_ids);
  gt.categories = {{1, "thing"}};
  gt.annotations = std::move(annotations);
  return gt;
}

CocoAnnotation Box(int64_t id, int64_t image, CocoBox box, bool crowd = false) {
  CocoAnnotation a;
  a.id = id;
  a.image_id = image;
  a.category_id = 1;
  a.bbox = box;
  a.area = box.width * box.height;
  a.iscrowd = crowd;
  return a;
}

CocoDetection Det(int64_t image, CocoBox box, double score, int64_t category = 1) {
  return {image, category, box, score};
}

// The summary indices.
enum Stat {
  kAp,
  kAp50,
  kAp75,
  kApSmall,
  kApMedium,
  kApLarge,
  kAr1,
  kAr10,
  kAr100,
  kArSmall,
  kArMedium,
  kArLarge
};

// pycocotools' precision of a run of true positives: tp / (tp + 0 + np.spacing(1)) is 1 - 2^-52
// when tp = 1, not 1.
const double kPerfect = 1.0 / (1.0 + std::numeric_limits<double>::epsilon());

// Area range indices of CocoAreaRanges().
constexpr int kAll = 0, kSmall = 1, kMedium = 2, kLarge = 3;

TEST(CocoTest, ThresholdsAreNumpysLinspace) {
  const std::vector<double> iou = CocoIouThresholds();
  ASSERT_EQ(iou.size(), 10u);
  EXPECT_EQ(iou[0], 0.5);
  EXPECT_EQ(iou[5], 0.75);                // so that summarize() finds AP75
  EXPECT_EQ(iou[8], 0.8999999999999999);  // numpy's value, not 0.9
  EXPECT_NE(iou[8], 0.9);
  EXPECT_EQ(iou[9], 0.95);
  const std::vector<double> recall = CocoRecallThresholds();
  ASSERT_EQ(recall.size(), 101u);
  EXPECT_EQ(recall[50], 0.5);
  EXPECT_EQ(recall[35], 35 * 0.01);
  EXPECT_NE(recall[35], 0.35);  // 0.35000000000000003 in numpy too
  EXPECT_EQ(recall[100], 1.0);
}

// The fixture of TwoBoxesThreeDetectionsByHand (below), which other tests reuse: two boxes on
// image 7 and three detections.
CocoGroundTruth TwoBoxes() {
  return OneCategory({7}, {Box(1, 7, {0, 0, 10, 10}), Box(2, 7, {20, 0, 10, 10})});
}
std::vector<CocoDetection> ThreeDetections() {
  return {Det(7, {0, 0, 10, 10}, 0.9), Det(7, {50, 50, 10, 10}, 0.8), Det(7, {21, 0, 10, 10}, 0.7)};
}

// Two boxes of one image and three detections, by hand. Highest score first: d1 covers gt 1
// (IoU 1), d2 covers nothing, d3 overlaps gt 2 with IoU 90 / 110 = 0.818. At thresholds <= 0.8
// the sequence is TP FP TP: recall 1/2, 1/2, 1, precision 1, 1/2, 2/3, whose envelope is 1, 2/3,
// 2/3; the 51 recall points 0.00..0.50 read 1, the 50 above read 2/3. At 0.85, 0.9 and 0.95 d3 is
// a FP: recall stops at 1/2 and the 50 points above read 0.
TEST(CocoTest, TwoBoxesThreeDetectionsByHand) {
  const CocoGroundTruth gt = TwoBoxes();
  const std::vector<CocoDetection> dets = ThreeDetections();
  const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
  const double ap_low = (51 * 1.0 + 50 * (2.0 / 3.0)) / 101;  // thresholds 0.5 .. 0.8
  const double ap_high = 51.0 / 101;                          // 0.85 .. 0.95
  const int m100 = 2;
  for (int t = 0; t < 10; ++t) {
    const bool low = t <= 6;
    EXPECT_EQ(r.precision[r.PrecisionIndex(t, 0, 0, kAll, m100)], kPerfect) << t;
    EXPECT_EQ(r.precision[r.PrecisionIndex(t, 50, 0, kAll, m100)], kPerfect) << t;
    EXPECT_EQ(r.precision[r.PrecisionIndex(t, 51, 0, kAll, m100)], low ? 2.0 / 3.0 : 0.0) << t;
    EXPECT_EQ(r.scores[r.PrecisionIndex(t, 51, 0, kAll, m100)], low ? 0.7 : 0.0) << t;
    EXPECT_EQ(r.recall[r.RecallIndex(t, 0, kAll, m100)], low ? 1.0 : 0.5) << t;
  }
  EXPECT_NEAR(r.stats[kAp], (7 * ap_low + 3 * ap_high) / 10, 1e-15);
  EXPECT_NEAR(r.stats[kAp50], ap_low, 1e-15);
  EXPECT_NEAR(r.stats[kAp75], ap_low, 1e-15);
  EXPECT_NEAR(r.stats[kApSmall], r.stats[kAp], 1e-15);  // both boxes are small (100 px^2)
  EXPECT_EQ(r.stats[kApMedium], -1);                    // no box there
  EXPECT_EQ(r.stats[kApLarge], -1);
  EXPECT_NEAR(r.stats[kAr1], 0.5, 1e-15);    // d1 alone
  EXPECT_NEAR(r.stats[kAr10], 0.85, 1e-15);  // 7 thresholds at 1, 3 at 1/2
  EXPECT_NEAR(r.stats[kAr100], 0.85, 1e-15);
  EXPECT_NEAR(r.stats[kArSmall], 0.85, 1e-15);
  EXPECT_EQ(r.stats[kArMedium], -1);
  EXPECT_EQ(r.num_gt, 2);
  EXPECT_EQ(r.num_detections, 3);
}

// A crowd region matches any number of detections by intersection over the detection's area, and
// a detection matched to it is ignored: neither a TP nor a FP.
TEST(CocoTest, CrowdRegionAbsorbsDetections) {
  const CocoGroundTruth gt =
      OneCategory({1}, {Box(1, 1, {0, 0, 100, 100}, /*crowd=*/true), Box(2, 1, {200, 0, 10, 10})});
  const std::vector<CocoDetection> dets = {
      Det(1, {10, 10, 20, 20}, 0.9), Det(1, {50, 50, 20, 20}, 0.8), Det(1, {200, 0, 10, 10}, 0.7)};
  const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
  EXPECT_NEAR(r.stats[kAp], 1.0, 1e-15);
  EXPECT_NEAR(r.stats[kAr100], 1.0, 1e-15);
  for (int t = 0; t < 10; ++t) {
    EXPECT_EQ(r.precision[r.PrecisionIndex(t, 100, 0, kAll, 2)], kPerfect);
  }

  // The same region not a crowd: an IoU of 400 / 10000, so both detections in it are false
  // positives, ranked first.
  CocoGroundTruth plain = gt;
  plain.annotations[0].iscrowd = false;
  const CocoEvalResult p = EvaluateCoco(plain, dets, CocoEvalOptions());
  // Two valid boxes now: recall 1/2, precision 1/3 until 0.50, then 0.
  EXPECT_NEAR(p.precision[p.PrecisionIndex(0, 0, 0, kAll, 2)], 1.0 / 3.0, 1e-15);
  EXPECT_EQ(p.precision[p.PrecisionIndex(0, 51, 0, kAll, 2)], 0.0);
  EXPECT_EQ(p.recall[p.RecallIndex(0, 0, kAll, 2)], 0.5);
}

// pycocotools sets a ground truth's ignore from its iscrowd alone (COCOeval._prepare): the file's
// "ignore" is not read unless honor_ignore_flag asks for it.
TEST(CocoTest, IgnoreFieldIsOverwrittenByIscrowd) {
  CocoAnnotation ignored = Box(1, 1, {0, 0, 10, 10});
  ignored.ignore = true;
  const CocoGroundTruth gt = OneCategory({1}, {ignored, Box(2, 1, {50, 0, 10, 10})});
  const std::vector<CocoDetection> dets = {Det(1, {50, 0, 10, 10}, 0.9)};
  const CocoEvalResult quirk = EvaluateCoco(gt, dets, CocoEvalOptions());
  EXPECT_NEAR(quirk.stats[kAr100], 0.5, 1e-15);  // the "ignored" box counts as missed
  CocoEvalOptions honor;
  honor.honor_ignore_flag = true;
  const CocoEvalResult fixed = EvaluateCoco(gt, dets, honor);
  EXPECT_NEAR(fixed.stats[kAr100], 1.0, 1e-15);
  EXPECT_NEAR(fixed.stats[kAp], 1.0, 1e-15);
}

// The area ranges go by the ground truth's "area" and the detection's box area. An unmatched
// detection outside a range is ignored there; inside it is a FP. One box per range (small 100,
// medium 2500, large 40000 px^2), each found, and an unmatched medium detection with the highest
// score: a FP first in "all" and "medium", ignored in the others.
TEST(CocoTest, AreaRangesByHand) {
  const CocoGroundTruth gt = OneCategory(
      {1}, {Box(1, 1, {0, 0, 10, 10}), Box(2, 1, {100, 0, 50, 50}), Box(3, 1, {300, 0, 200, 200})});
  const std::vector<CocoDetection> dets = {
      Det(1, {0, 600, 50, 50}, 0.95),  // medium, matches nothing
      Det(1, {0, 0, 10, 10}, 0.9), Det(1, {100, 0, 50, 50}, 0.8), Det(1, {300, 0, 200, 200}, 0.7)};
  const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
  EXPECT_NEAR(r.stats[kApSmall], 1.0, 1e-15);  // the FP is ignored: outside, unmatched
  EXPECT_NEAR(r.stats[kApLarge], 1.0, 1e-15);
  // Medium: FP then TP: precision 0 then 1/2; the envelope is 1/2 at every recall point.
  EXPECT_NEAR(r.stats[kApMedium], 0.5, 1e-15);
  // All: FP, TP, TP, TP: precision 0, 1/2, 2/3, 3/4 at recall 0, 1/3, 2/3, 1: the envelope is 3/4
  // everywhere.
  EXPECT_NEAR(r.stats[kAp], 0.75, 1e-15);
  // In the small range the medium and large ground truths are ignored and their detections,
  // matched to ignored boxes, are ignored too.
  EXPECT_EQ(r.recall[r.RecallIndex(0, 0, kSmall, 2)], 1.0);
  // The ground truth's area, not its box's, decides: the small box declared 5000 px^2 is medium.
  CocoGroundTruth declared = gt;
  declared.annotations[0].area = 5000;
  const CocoEvalResult d = EvaluateCoco(declared, dets, CocoEvalOptions());
  EXPECT_EQ(d.stats[kApSmall], -1);  // no small ground truth left
  EXPECT_EQ(d.recall[d.RecallIndex(0, 0, kMedium, 2)], 1.0);
}

// max_dets keeps the highest-scored detections per image and category: AR@1 counts only the
// first of each image.
TEST(CocoTest, MaxDetsPerImage) {
  const CocoGroundTruth gt = OneCategory(
      {1, 2}, {Box(1, 1, {0, 0, 10, 10}), Box(2, 2, {0, 0, 10, 10}), Box(3, 2, {50, 0, 10, 10})});
  const std::vector<CocoDetection> dets = {
      Det(1, {0, 0, 10, 10}, 0.5),  // image 1: found by its only detection
      Det(2, {90, 90, 5, 5}, 0.9),  // image 2: a FP first...
      Det(2, {0, 0, 10, 10}, 0.8),  // ...then both boxes
      Det(2, {50, 0, 10, 10}, 0.6)};
  const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
  EXPECT_NEAR(r.stats[kAr1], 1.0 / 3.0, 1e-15);  // image 1's box; image 2's FP
  EXPECT_NEAR(r.stats[kAr10], 1.0, 1e-15);
  // maxDets 1: scores 0.9 (FP), 0.5 (TP): recall 0, 1/3; precision 0, 1/2, enveloped to 1/2 up
  // to recall 1/3 (34 points 0.00..0.33), 0 above.
  EXPECT_NEAR(r.precision[r.PrecisionIndex(0, 33, 0, kAll, 0)], 0.5, 1e-15);
  EXPECT_EQ(r.precision[r.PrecisionIndex(0, 34, 0, kAll, 0)], 0.0);
  CocoEvalOptions options;
  options.max_dets = {1, 2, 5};
  const CocoEvalResult small = EvaluateCoco(gt, dets, options);
  // AR@2 misses image 2's third detection; stats[0] still looks for maxDets 100 (pycocotools'
  // quirk): -1.
  EXPECT_NEAR(small.stats[kAr10], 2.0 / 3.0, 1e-15);
  EXPECT_EQ(small.stats[kAp], -1);
  EXPECT_NE(small.stats[kAp50], -1);
  EXPECT_NE(FormatCocoSummary(small).find("maxDets=  2 ] = 0.667"), std::string::npos);
}

// Ties in score keep file order (numpy's stable sort), across images in image-id order.
TEST(CocoTest, ScoreTiesKeepFileOrder) {
  const CocoGroundTruth gt = OneCategory({1}, {Box(1, 1, {0, 0, 10, 10})});
  // Same score: the FP listed first is ranked first, so precision at recall 1 is 1/2.
  const CocoEvalResult fp_first = EvaluateCoco(
      gt, {Det(1, {50, 50, 10, 10}, 0.5), Det(1, {0, 0, 10, 10}, 0.5)}, CocoEvalOptions());
  EXPECT_NEAR(fp_first.stats[kAp], 0.5, 1e-15);
  const CocoEvalResult tp_first = EvaluateCoco(
      gt, {Det(1, {0, 0, 10, 10}, 0.5), Det(1, {50, 50, 10, 10}, 0.5)}, CocoEvalOptions());
  EXPECT_NEAR(tp_first.stats[kAp], 1.0, 1e-15);
}

// A ground truth with id 0 is never found: pycocotools records a match by the matched id, and 0
// reads as no match (reproduced).
TEST(CocoTest, GroundTruthIdZeroIsNeverFound) {
  const CocoGroundTruth gt = OneCategory({1}, {Box(0, 1, {0, 0, 10, 10})});
  const CocoEvalResult r = EvaluateCoco(gt, {Det(1, {0, 0, 10, 10}, 0.9)}, CocoEvalOptions());
  EXPECT_EQ(r.recall[r.RecallIndex(0, 0, kAll, 2)], 0.0);
  EXPECT_EQ(r.stats[kAp], 0.0);
}

// -1 for a category without ground truth (in an area range), 0 for one whose boxes are all missed,
// and a category without ground truth does not enter the means.
TEST(CocoTest, EmptyCategoriesAndImages) {
  CocoGroundTruth gt = OneCategory({1, 2, 3}, {Box(1, 1, {0, 0, 10, 10})});
  gt.categories.push_back({2, "other"});   // no ground truth; a detection of it
  gt.categories.push_back({3, "unseen"});  // nothing at all
  const std::vector<CocoDetection> dets = {Det(1, {0, 0, 10, 10}, 0.9),
                                           Det(2, {0, 0, 10, 10}, 0.9, /*category=*/2),
                                           Det(3, {0, 0, 10, 10}, 0.9, /*category=*/7)};
  const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
  ASSERT_EQ(r.category_ids, (std::vector<int64_t>{1, 2, 3}));
  EXPECT_EQ(r.num_detections, 2);
  EXPECT_EQ(r.num_detections_skipped, 1);  // category 7 is not in the ground truth
  for (int k : {1, 2}) {
    EXPECT_EQ(r.precision[r.PrecisionIndex(0, 0, k, kAll, 2)], -1) << k;
    EXPECT_EQ(r.recall[r.RecallIndex(0, k, kAll, 2)], -1) << k;
  }
  EXPECT_NEAR(r.stats[kAp], 1.0, 1e-15);

  // No detection at all (pycocotools' loadRes fails on an empty list): zeros, not -1.
  const CocoEvalResult none = EvaluateCoco(gt, {}, CocoEvalOptions());
  EXPECT_EQ(none.stats[kAp], 0.0);
  EXPECT_EQ(none.stats[kAr100], 0.0);
  EXPECT_EQ(none.stats[kApMedium], -1);
}

// A random COCO-shaped set: 300 boxes of every size on 20 images in 5 categories, every 17th a
// crowd; per box a detection on it (every third shifted a little) and one anywhere, scores
// uniform in [0, 1].
struct RandomCocoSet {
  CocoGroundTruth gt;
  std::vector<CocoDetection> dets;
};

RandomCocoSet MakeRandomCocoSet() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(0, 200), size(2, 120), score(0, 1);
  RandomCocoSet set;
  CocoGroundTruth& gt = set.gt;
  gt.source = "random";
  for (int64_t i = 1; i <= 20; ++i) gt.image_ids.push_back(i);
  for (int64_t k = 1; k <= 5; ++k) gt.categories.push_back({k, ""});
  for (int i = 0; i < 300; ++i) {
    CocoAnnotation a =
        Box(i + 1, 1 + i % 20, {coord(rng), coord(rng), size(rng), size(rng)}, i % 17 == 0);
    a.category_id = 1 + i % 5;
    gt.annotations.push_back(a);
    const CocoBox jitter = {a.bbox.x + size(rng) / 20, a.bbox.y, a.bbox.width, a.bbox.height};
    set.dets.push_back(Det(a.image_id, i % 3 == 0 ? jitter : a.bbox, score(rng), a.category_id));
    set.dets.push_back(
        Det(1 + i % 20, {coord(rng), coord(rng), size(rng), size(rng)}, score(rng), 1 + i % 5));
  }
  return set;
}

// The results depend neither on the number of threads nor on the order of the categories' ids.
TEST(CocoTest, ThreadsDoNotChangeTheResult) {
  const RandomCocoSet set = MakeRandomCocoSet();
  const CocoGroundTruth& gt = set.gt;
  const std::vector<CocoDetection>& dets = set.dets;
  CocoEvalOptions one, many;
  one.num_threads = 1;
  many.num_threads = 4;
  const CocoEvalResult a = EvaluateCoco(gt, dets, one);
  const CocoEvalResult b = EvaluateCoco(gt, dets, many);
  EXPECT_EQ(a.precision, b.precision);
  EXPECT_EQ(a.recall, b.recall);
  EXPECT_EQ(a.scores, b.scores);
  EXPECT_EQ(a.stats, b.stats);
  EXPECT_GT(a.stats[kAp], 0.1);
  EXPECT_LT(a.stats[kAp], 1.0);
}

// The case greedy matching loses: d1 (highest score) overlaps gt 1 and, more, gt 2; d2 overlaps
// gt 2 only. pycocotools gives d1 its best, gt 2, and d2 is a FP: recall 1/2 at
// IoU 0.5. The optimal matcher pairs d1 with gt 1 and d2 with gt 2: recall 1, precision 1.
TEST(CocoTest, OptimalMatcherFindsBothBoxesGreedyFindsOne) {
  // Boxes of full height that overlap in x only: gt 1 = [0, 10], gt 2 = [4, 14].
  const CocoGroundTruth gt =
      OneCategory({1}, {Box(1, 1, {0, 0, 10, 10}), Box(2, 1, {4, 0, 10, 10})});
  // d1 = [3, 13]: with gt 1 7/13 = 0.538, with gt 2 9/11 = 0.818. d2 = [5, 15]: with gt 1 5/15,
  // with gt 2 9/11.
  const std::vector<CocoDetection> dets = {Det(1, {3, 0, 10, 10}, 0.9),
                                           Det(1, {5, 0, 10, 10}, 0.8)};
  CocoEvalOptions greedy, optimal;
  greedy.iou_thresholds = optimal.iou_thresholds = {0.5};
  optimal.matcher = CocoMatcher::kOptimal;
  const CocoEvalResult g = EvaluateCoco(gt, dets, greedy);
  const CocoEvalResult o = EvaluateCoco(gt, dets, optimal);
  EXPECT_EQ(g.recall[g.RecallIndex(0, 0, kAll, 2)], 0.5);
  EXPECT_EQ(o.recall[o.RecallIndex(0, 0, kAll, 2)], 1.0);
  // Greedy: TP then FP; the 51 points up to recall 1/2 read precision 1, the rest 0.
  EXPECT_NEAR(g.stats[kAp], 51.0 / 101, 1e-15);
  // Optimal: after d1 alone one TP (d1 with either box), after d2 two, whose precision 2 / (2 +
  // 2^-52) rounds to 1 and lifts the envelope: 1 everywhere.
  EXPECT_EQ(o.precision[o.PrecisionIndex(0, 0, 0, kAll, 2)], 1.0);
  EXPECT_EQ(o.precision[o.PrecisionIndex(0, 100, 0, kAll, 2)], 1.0);
  EXPECT_EQ(o.scores[o.PrecisionIndex(0, 100, 0, kAll, 2)], 0.8);
  EXPECT_EQ(o.stats[kAp], 1.0);
}

// A box outside the area range excuses any number of detections under the optimal matcher, as a
// crowd does in both; pycocotools lets it excuse one, and the next is a FP. A small box (31 x 32 =
// 992 px^2) and two detections on it just inside "medium" (33 x 32 = 1056, IoU 0.94), scored above
// the detection of a medium box: in "medium" pycocotools counts ignored, FP, TP (precision 1/2 at
// recall 1), the optimal matcher ignored, ignored, TP.
TEST(CocoTest, OptimalMatcherIgnoredBoxesExcuseAnyNumber) {
  const CocoGroundTruth gt =
      OneCategory({1}, {Box(1, 1, {0, 0, 31, 32}), Box(2, 1, {100, 100, 40, 40})});
  const std::vector<CocoDetection> dets = {
      Det(1, {0, 0, 33, 32}, 0.95), Det(1, {0, 0, 33, 32}, 0.9), Det(1, {100, 100, 40, 40}, 0.8)};
  CocoEvalOptions greedy, optimal;
  optimal.matcher = CocoMatcher::kOptimal;
  const CocoEvalResult g = EvaluateCoco(gt, dets, greedy);
  const CocoEvalResult o = EvaluateCoco(gt, dets, optimal);
  EXPECT_EQ(g.precision[g.PrecisionIndex(0, 100, 0, kMedium, 2)], 0.5);
  EXPECT_EQ(o.precision[o.PrecisionIndex(0, 100, 0, kMedium, 2)], kPerfect);
  EXPECT_EQ(g.recall[g.RecallIndex(0, 0, kMedium, 2)], 1.0);
  EXPECT_EQ(o.recall[o.RecallIndex(0, 0, kMedium, 2)], 1.0);
  // In "all" the second detection on the small box is a duplicate, a FP for both matchers.
  EXPECT_EQ(g.precision[g.PrecisionIndex(0, 100, 0, kAll, 2)], 2.0 / 3.0);
  EXPECT_EQ(o.precision[o.PrecisionIndex(0, 100, 0, kAll, 2)], 2.0 / 3.0);
}

// Brute force over every matching of the first p detections of a small random cell: the most TPs,
// then the fewest FPs (detections in no pair that nothing excuses), then the largest IoU sum.
struct BruteBest {
  int tp = -1, fp = 0;
  double iou_sum = 0;
};

void BruteForce(const CocoImageCell& c, double tau, int p, int d, std::vector<char>* used, int tp,
                int fp, double iou_sum, const std::vector<char>& excusable, BruteBest* best) {
  if (d == p) {
    if (tp > best->tp || (tp == best->tp && fp < best->fp) ||
        (tp == best->tp && fp == best->fp && iou_sum > best->iou_sum + 1e-12)) {
      *best = {tp, fp, iou_sum};
    }
    return;
  }
  BruteForce(c, tau, p, d + 1, used, tp, fp + (excusable[d] ? 0 : 1), iou_sum, excusable, best);
  for (int g = 0; g < c.num_gts; ++g) {
    const double iou = c.iou[d * c.num_gts + g];
    if (!c.gt_valid[g] || (*used)[g] || iou < tau) continue;
    (*used)[g] = 1;
    BruteForce(c, tau, p, d + 1, used, tp + 1, fp, iou_sum + iou, excusable, best);
    (*used)[g] = 0;
  }
}

TEST(CocoTest, OptimalMatcherAgainstBruteForceOnEveryPrefix) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  CocoOptimalMatcher matcher;
  std::vector<uint8_t> flags;
  std::vector<int32_t> det_gt;
  std::vector<uint8_t> assoc_flags;
  int cells_with_conflict = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int D = 1 + static_cast<int>(rng() % 6), G = static_cast<int>(rng() % 5);
    std::vector<double> iou(D * G);
    for (double& v : iou) v = unit(rng) < 0.5 ? 0.0 : 0.3 + 0.7 * unit(rng);
    std::vector<uint8_t> gt_valid(G), det_outside(D);
    for (uint8_t& v : gt_valid) v = unit(rng) < 0.75;
    for (uint8_t& v : det_outside) v = unit(rng) < 0.2;
    const CocoImageCell cell{D, G, iou.data(), gt_valid.data(), det_outside.data()};
    const double tau = 0.5;
    std::vector<char> excusable(D);
    for (int d = 0; d < D; ++d) {
      excusable[d] = det_outside[d];
      for (int g = 0; g < G; ++g) excusable[d] |= !gt_valid[g] && iou[d * G + g] >= tau;
    }
    matcher.Outcomes(cell, tau, &flags);
    ASSERT_EQ(flags.size(), static_cast<size_t>(D));
    int tp = 0, fp = 0;
    for (int p = 1; p <= D; ++p) {
      tp += flags[p - 1] == kCocoMatched;
      fp += flags[p - 1] == 0;
      BruteBest best;
      std::vector<char> used(G, 0);
      BruteForce(cell, tau, p, 0, &used, 0, 0, 0.0, excusable, &best);
      ASSERT_EQ(tp, best.tp) << "trial " << trial << " prefix " << p;
      ASSERT_EQ(fp, best.fp) << "trial " << trial << " prefix " << p;
      // The association of the prefix: the same counts, and the largest IoU sum among them.
      matcher.Associate(cell, tau, p, &det_gt, &assoc_flags);
      int a_tp = 0, a_fp = 0;
      double a_iou = 0;
      std::vector<char> gt_used(G, 0);
      for (int d = 0; d < D; ++d) {
        if (d >= p) {
          ASSERT_EQ(det_gt[d], -1);
          ASSERT_EQ(assoc_flags[d], kCocoIgnored);
          continue;
        }
        ASSERT_EQ(assoc_flags[d], det_gt[d] >= 0 ? kCocoMatched : excusable[d] ? kCocoIgnored : 0);
        if (det_gt[d] >= 0) {
          const int g = det_gt[d];
          ASSERT_TRUE(gt_valid[g]);
          ASSERT_GE(iou[d * G + g], tau);
          ASSERT_FALSE(gt_used[g]);
          gt_used[g] = 1;
          ++a_tp;
          a_iou += iou[d * G + g];
        } else if (!excusable[d]) {
          ++a_fp;
        }
      }
      ASSERT_EQ(a_tp, best.tp);
      ASSERT_EQ(a_fp, best.fp);
      ASSERT_NEAR(a_iou, best.iou_sum, 1e-12);
    }
    // Count the cells where the greedy choice could go wrong (a detection with two candidates).
    for (int d = 0; d < D; ++d) {
      int candidates = 0;
      for (int g = 0; g < G; ++g) candidates += gt_valid[g] && iou[d * G + g] >= tau;
      cells_with_conflict += candidates > 1;
    }
  }
  EXPECT_GT(cells_with_conflict, 50);
}

// On random sets the optimal matcher's recall is never below pycocotools' (each prefix of each
// image has at least the greedy TPs), and where every detection overlaps at most one ground truth
// and every ground truth at most one detection, the two agree on every array.
TEST(CocoTest, OptimalMatcherNeverFindsLessAndAgreesWithoutConflicts) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(0, 200), size(20, 100), score(0, 1);
  CocoGroundTruth gt;
  gt.source = "random";
  for (int64_t i = 1; i <= 20; ++i) gt.image_ids.push_back(i);
  for (int64_t k = 1; k <= 2; ++k) gt.categories.push_back({k, ""});
  std::vector<CocoDetection> crowded, separate;
  for (int i = 0; i < 600; ++i) {
    CocoAnnotation a = Box(i + 1, 1 + i % 20, {coord(rng), coord(rng), size(rng), size(rng)});
    a.category_id = 1 + i % 2;
    gt.annotations.push_back(a);
    const CocoBox shifted = {a.bbox.x + a.bbox.width * 0.4 * score(rng), a.bbox.y, a.bbox.width,
                             a.bbox.height};
    crowded.push_back(Det(a.image_id, shifted, score(rng), a.category_id));
    crowded.push_back(
        Det(a.image_id, {coord(rng), coord(rng), size(rng), size(rng)}, score(rng), a.category_id));
  }
  CocoEvalOptions greedy, optimal;
  optimal.matcher = CocoMatcher::kOptimal;
  const CocoEvalResult g = EvaluateCoco(gt, crowded, greedy);
  const CocoEvalResult o = EvaluateCoco(gt, crowded, optimal);
  int larger = 0;
  for (size_t i = 0; i < g.recall.size(); ++i) {
    ASSERT_GE(o.recall[i], g.recall[i]) << i;
    larger += o.recall[i] > g.recall[i];
  }
  EXPECT_GT(larger, 0);
  EXPECT_GE(o.stats[kAr100], g.stats[kAr100]);

  // One box per image, far apart from the others, and detections on it or far away.
  CocoGroundTruth sparse;
  sparse.source = "sparse";
  sparse.categories = {{1, ""}};
  for (int64_t i = 1; i <= 50; ++i) {
    sparse.image_ids.push_back(i);
    sparse.annotations.push_back(Box(i, i, {10, 10, size(rng), size(rng)}));
    const CocoBox& b = sparse.annotations.back().bbox;
    separate.push_back(
        Det(i, {b.x + b.width * 0.3 * score(rng), b.y, b.width, b.height}, score(rng)));
    separate.push_back(Det(i, {1000, 1000, size(rng), size(rng)}, score(rng)));
  }
  const CocoEvalResult gs = EvaluateCoco(sparse, separate, greedy);
  const CocoEvalResult os = EvaluateCoco(sparse, separate, optimal);
  EXPECT_EQ(gs.precision, os.precision);
  EXPECT_EQ(gs.recall, os.recall);
  EXPECT_EQ(gs.scores, os.scores);
  EXPECT_EQ(gs.stats, os.stats);
}

// The operating-point cells of TwoBoxesThreeDetectionsByHand: d1 (0.9) TP, d2 (0.8) FP, d3 (0.7) TP
// at IoU <= 0.8; d3 a FP above.
TEST(CocoTest, ScoreMetricsByHand) {
  const CocoGroundTruth gt = TwoBoxes();
  const std::vector<CocoDetection> dets = ThreeDetections();
  for (const CocoMatcher matcher : {CocoMatcher::kCoco, CocoMatcher::kOptimal}) {
    SCOPED_TRACE(CocoMatcherName(matcher));
    CocoEvalOptions options;
    options.matcher = matcher;
    options.score_metrics = true;
    const CocoEvalResult r = EvaluateCoco(gt, dets, options);
    ASSERT_EQ(r.cells.size(), 10u * 1 * 4);
    const CocoCell& low = r.cells[r.CellIndex(0, 0, kAll)];
    EXPECT_EQ(low.num_valid_gt, 2);
    EXPECT_EQ(low.at_threshold.tp, 2);
    EXPECT_EQ(low.at_threshold.fp, 1);
    EXPECT_EQ(low.at_threshold.fn, 0);
    EXPECT_NEAR(low.brier.over_labels, (0.01 + 0.09) / 2, 1e-15);
    EXPECT_NEAR(low.brier.over_detections, (0.01 + 0.64 + 0.09) / 3, 1e-15);
    EXPECT_NEAR(low.brier.over_all, (0.01 + 0.09 + 0.64) / 3, 1e-15);
    EXPECT_EQ(low.brier.num_label_terms, 2);
    EXPECT_EQ(low.brier.num_all_terms, 3);
    // Bins 9 (a TP at 0.9), 8 (a FP at 0.8) and 7 (a TP at 0.7).
    EXPECT_NEAR(low.calibration.ece, (0.1 + 0.8 + 0.3) / 3, 1e-15);
    EXPECT_EQ(low.calibration.bins[8].count, 1);
    EXPECT_EQ(low.calibration.bins[8].tp_fraction, 0.0);
    const CocoCell& high = r.cells[r.CellIndex(9, 0, kAll)];  // IoU 0.95: d3 a FP
    EXPECT_EQ(high.at_threshold.tp, 1);
    EXPECT_EQ(high.at_threshold.fp, 2);
    EXPECT_EQ(high.at_threshold.fn, 1);
    EXPECT_NEAR(high.brier.over_labels, (0.01 + 1) / 2, 1e-15);
    EXPECT_NEAR(high.brier.over_all, (0.01 + 1 + 0.64 + 0.49) / 4, 1e-15);
    // No ground truth in "medium": no label term, and the detections are all outside the range.
    const CocoCell& medium = r.cells[r.CellIndex(0, 0, kMedium)];
    EXPECT_EQ(medium.num_valid_gt, 0);
    EXPECT_TRUE(std::isnan(medium.brier.over_labels));
    EXPECT_EQ(medium.at_threshold.fp, 0);
    // The summary: the mean over the thresholds (7 low, 3 high) and the one category.
    EXPECT_NEAR(r.score_stats[0], (7 * 0.05 + 3 * 0.505) / 10, 1e-15);  // BL
    EXPECT_NEAR(r.score_stats[1], 0.05, 1e-15);                         // BL50
    EXPECT_NEAR(r.score_stats[2], 0.05, 1e-15);                         // BL75
    EXPECT_NEAR(r.score_stats[10], 0.4, 1e-15);                         // ECE50
    // The AP arrays do not depend on the cells.
    CocoEvalOptions plain;
    plain.matcher = matcher;
    const CocoEvalResult p = EvaluateCoco(gt, dets, plain);
    EXPECT_EQ(p.precision, r.precision);
    EXPECT_EQ(p.stats, r.stats);
    EXPECT_TRUE(p.cells.empty());
    EXPECT_EQ(p.score_stats[0], -1);

    // At the operating point 0.75 d3 takes no part: gt 2 is a FN.
    options.score_threshold = 0.75;
    const CocoEvalResult t = EvaluateCoco(gt, dets, options);
    const CocoCell& cut = t.cells[t.CellIndex(0, 0, kAll)];
    EXPECT_EQ(cut.at_threshold.tp, 1);
    EXPECT_EQ(cut.at_threshold.fp, 1);
    EXPECT_EQ(cut.at_threshold.fn, 1);
    EXPECT_NEAR(cut.brier.over_labels, (0.01 + 1) / 2, 1e-15);
    EXPECT_EQ(t.stats, r.stats);
  }
}

// Scores that are not probabilities leave the Brier scores out unless a transform makes them so.
TEST(CocoTest, ScoreMetricsNeedProbabilities) {
  const CocoGroundTruth gt = OneCategory({1}, {Box(1, 1, {0, 0, 10, 10})});
  const std::vector<CocoDetection> dets = {Det(1, {0, 0, 10, 10}, 2.0)};
  CocoEvalOptions options;
  options.score_metrics = true;
  const CocoEvalResult raw = EvaluateCoco(gt, dets, options);
  EXPECT_FALSE(raw.probability_metrics);
  EXPECT_TRUE(std::isnan(raw.cells[raw.CellIndex(0, 0, kAll)].brier.over_labels));
  EXPECT_EQ(raw.cells[raw.CellIndex(0, 0, kAll)].at_threshold.tp, 1);  // counts stay
  EXPECT_EQ(raw.score_stats[0], -1);
  options.score_transform = ScoreTransform::kSigmoid;
  const CocoEvalResult logits = EvaluateCoco(gt, dets, options);
  EXPECT_TRUE(logits.probability_metrics);
  const double p = 1 / (1 + std::exp(-2.0));
  EXPECT_NEAR(logits.score_stats[0], (1 - p) * (1 - p), 1e-15);
}

// On random sets, for both matchers: at the lowest operating point a cell's TPs are the recall
// array's (with max_dets.back()) times its valid ground truths, TP + FN is that count, and the
// FPs are the precision's complement at the last detection.
TEST(CocoTest, ScoreMetricsAgreeWithTheArrays) {
  const RandomCocoSet set = MakeRandomCocoSet();
  const CocoGroundTruth& gt = set.gt;
  const std::vector<CocoDetection>& dets = set.dets;
  for (const CocoMatcher matcher : {CocoMatcher::kCoco, CocoMatcher::kOptimal}) {
    SCOPED_TRACE(CocoMatcherName(matcher));
    CocoEvalOptions options;
    options.matcher = matcher;
    options.score_metrics = true;
    const CocoEvalResult r = EvaluateCoco(gt, dets, options);
    int checked = 0;
    for (int t = 0; t < 10; ++t) {
      for (int k = 0; k < static_cast<int>(r.category_ids.size()); ++k) {
        for (int a = 0; a < 4; ++a) {
          const CocoCell& cell = r.cells[r.CellIndex(t, k, a)];
          if (cell.num_valid_gt == 0) continue;
          const double recall = r.recall[r.RecallIndex(t, k, a, 2)];
          EXPECT_EQ(cell.at_threshold.tp,
                    std::llround(recall * static_cast<double>(cell.num_valid_gt)));
          EXPECT_EQ(cell.at_threshold.tp + cell.at_threshold.fn, cell.num_valid_gt);
          EXPECT_EQ(cell.brier.num_label_terms, cell.num_valid_gt);
          EXPECT_EQ(cell.brier.num_detection_terms, cell.at_threshold.tp + cell.at_threshold.fp);
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 100);
    EXPECT_GT(r.score_stats[0], 0);
    EXPECT_LT(r.score_stats[0], 1);
    // The threads do not change the cells.
    options.num_threads = 1;
    const CocoEvalResult one = EvaluateCoco(gt, dets, options);
    EXPECT_EQ(one.score_stats, r.score_stats);
  }
}

// Each category's 12 numbers are summarize() over that category alone: equal to the whole
// evaluation's with one category, and the whole AP is the mean of the categories' where the
// categories' slices are the same size.
TEST(CocoTest, CategoryStatsAreEachCategorysSummary) {
  const CocoGroundTruth one = TwoBoxes();
  const std::vector<CocoDetection> dets = ThreeDetections();
  const CocoEvalResult r = EvaluateCoco(one, dets, CocoEvalOptions());
  ASSERT_EQ(r.category_stats.size(), 1u);
  EXPECT_EQ(r.category_stats[0], r.stats);
  // Two categories, the second found perfectly: its AP 1, the first's as above.
  CocoGroundTruth two = one;
  two.categories.push_back({2, "other"});
  CocoAnnotation b = Box(3, 7, {100, 100, 20, 20});
  b.category_id = 2;
  two.annotations.push_back(b);
  std::vector<CocoDetection> more = dets;
  more.push_back(Det(7, {100, 100, 20, 20}, 0.5, 2));
  const CocoEvalResult t = EvaluateCoco(two, more, CocoEvalOptions());
  ASSERT_EQ(t.category_stats.size(), 2u);
  EXPECT_EQ(t.category_stats[0], r.stats);
  EXPECT_NEAR(t.category_stats[1][kAp], kPerfect, 1e-15);
  EXPECT_NEAR(t.stats[kAp], (r.stats[kAp] + t.category_stats[1][kAp]) / 2, 1e-15);
  const std::string table = FormatCocoCategories(t);
  EXPECT_NE(table.find("category                   id     AP   AP50   AP75    APs    APm    APl"
                       "  AR100\n"),
            std::string::npos)
      << table;
  EXPECT_NE(table.find("\nother                       2  1.000  1.000  1.000  1.000      -      -"
                       "  1.000\n"),
            std::string::npos)
      << table;
}

TEST(CocoTest, MatcherNames) {
  EXPECT_STREQ(CocoMatcherName(CocoMatcher::kCoco), "coco");
  EXPECT_STREQ(CocoMatcherName(CocoMatcher::kOptimal), "optimal");
  EXPECT_EQ(ParseCocoMatcher("optimal"), CocoMatcher::kOptimal);
  EXPECT_EQ(ParseCocoMatcher("greedy"), CocoMatcher::kCoco);
  EXPECT_EQ(ParseCocoMatcher("coco"), CocoMatcher::kCoco);
  EXPECT_FALSE(ParseCocoMatcher("kitti").has_value());
}

TEST(CocoTest, SummaryInPycocotoolsLayout) {
  const CocoGroundTruth gt = OneCategory({1}, {Box(1, 1, {0, 0, 10, 10})});
  const CocoEvalResult r = EvaluateCoco(gt, {Det(1, {0, 0, 10, 10}, 0.9)}, CocoEvalOptions());
  const std::string summary = FormatCocoSummary(r);
  EXPECT_EQ(summary.substr(0, summary.find('\n') + 1),
            " Average Precision  (AP) @[ IoU=0.50:0.95 | area=   all | maxDets=100 ] = 1.000\n");
  EXPECT_NE(summary.find(" Average Precision  (AP) @[ IoU=0.75      | area=   all | maxDets=100 ]"
                         " = 1.000\n"),
            std::string::npos);
  EXPECT_NE(summary.find(" Average Recall     (AR) @[ IoU=0.50:0.95 | area= large | maxDets=100 ]"
                         " = -1.000\n"),
            std::string::npos);
  EXPECT_EQ(std::count(summary.begin(), summary.end(), '\n'), kNumCocoStats);

  // With the operating-point metrics, 12 more lines in the same columns: a detection of score 0.9
  // on its box gives Brier over labels 0.01.
  CocoEvalOptions options;
  options.score_metrics = true;
  const std::string more =
      FormatCocoSummary(EvaluateCoco(gt, {Det(1, {0, 0, 10, 10}, 0.9)}, options));
  EXPECT_EQ(std::count(more.begin(), more.end(), '\n'), kNumCocoStats + kNumCocoScoreStats);
  EXPECT_EQ(more.substr(0, summary.size()), summary);
  EXPECT_NE(more.find(" Brier over labels  (BL) @[ IoU=0.50:0.95 | area=   all | maxDets=100 ]"
                      " = 0.010\n"),
            std::string::npos);
  EXPECT_NE(more.find(" Calibration error (ECE) @[ IoU=0.75      | area=   all | maxDets=100 ]"
                      " = 0.100\n"),
            std::string::npos);
}

TEST(CocoTest, ParsesGroundTruthAndResults) {
  // Unread keys are skipped whatever they hold; a repeated key counts its last value, a repeated
  // category id its last category (as Python's json and COCO.createIndex do).
  const std::string gt_text = R"({
    "info": {"year": 2017, "nested": [1, {"a": [[]]}], "images": 7},
    "images": [{"id": 3, "file_name": "a.jpg"}, {"id": 1}, {"id": 3}],
    "categories": [{"id": 5, "name": "dog"}, {"id": 2}, {"id": 5, "name": "cat"}],
    "annotations": [
      {"id": 10, "image_id": 1, "category_id": 5, "bbox": [1, 2.5, 3, 4], "area": 2,
       "iscrowd": 0, "segmentation": [[1, 2, 3, 4]], "area": 11.5},
      {"id": 11, "image_id": 3, "category_id": 5, "bbox": [0, 0, 9, 9], "area": 81,
       "iscrowd": 1, "ignore": 1}]})";
  const CocoGroundTruth gt = ParseCocoGroundTruth(gt_text, "gt.json");
  EXPECT_EQ(gt.image_ids, (std::vector<int64_t>{1, 3}));
  ASSERT_EQ(gt.categories.size(), 2u);
  EXPECT_EQ(gt.categories[0].id, 2);
  EXPECT_EQ(gt.categories[0].name, "");
  EXPECT_EQ(gt.categories[1].name, "cat");
  ASSERT_EQ(gt.annotations.size(), 2u);
  EXPECT_EQ(gt.annotations[0].bbox.y, 2.5);
  EXPECT_EQ(gt.annotations[0].area, 11.5);
  EXPECT_FALSE(gt.annotations[0].iscrowd);
  EXPECT_TRUE(gt.annotations[1].iscrowd);
  EXPECT_TRUE(gt.annotations[1].ignore);
  const std::vector<CocoDetection> dets = ParseCocoDetections(
      R"([{"image_id": 3, "category_id": 5, "bbox": [0, 0, 9, 9], "score": 0.25, "id": 99}])",
      "det.json", gt);
  ASSERT_EQ(dets.size(), 1u);
  EXPECT_EQ(dets[0].score, 0.25);
  EXPECT_EQ(dets[0].bbox.width, 9);
}

// The message of the ParseError `text` raises, or "" if it raises none.
template <typename Fn>
std::string ParseErrorOf(Fn fn) {
  try {
    fn();
  } catch (const ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(CocoTest, BadFilesNameTheFileAndField) {
  const std::string images = R"("images": [{"id": 1}], "categories": [{"id": 1}])";
  EXPECT_EQ(ParseErrorOf([&] {
              ParseCocoGroundTruth("{" + images + R"(, "annotations": [{"id": 1, "image_id": 1,
                "category_id": 1, "bbox": [0, 0, 1], "area": 1}]})",
                                   "gt.json");
            }),
            "gt.json: field annotations[0].bbox: expected 4 numbers [x, y, width, height], got "
            "[0,0,1]");
  EXPECT_EQ(ParseErrorOf([&] {
              ParseCocoGroundTruth("{" + images + R"(, "annotations": [{"id": 1, "image_id": 1,
                "category_id": 1, "bbox": [0, 0, 1, 1]}]})",
                                   "gt.json");
            }),
            "gt.json: field annotations[0].area: missing");
  EXPECT_NE(ParseErrorOf([&] {
              ParseCocoGroundTruth("{" + images + R"(, "annotations": [
                  {"id": 4, "image_id": 1, "category_id": 1, "bbox": [0, 0, 1, 1], "area": 1},
                  {"id": 4, "image_id": 1, "category_id": 1, "bbox": [0, 0, 1, 1], "area": 1}]})",
                                   "gt.json");
            }).find("annotations[1].id: id 4 is also annotations[0]'s"),
            std::string::npos);
  EXPECT_EQ(ParseErrorOf([] { ParseCocoGroundTruth(R"({"images": [{"id": "x"}]})", "gt.json"); }),
            "gt.json: field images[0].id: expected an integer id, got \"x\"");
  EXPECT_EQ(ParseErrorOf([] {
              ParseCocoGroundTruth("{\n\"images\": [,]}", "gt.json");
            }).rfind("gt.json:2: not valid JSON", 0),
            0u);
  const CocoGroundTruth gt = ParseCocoGroundTruth("{" + images + "}", "gt.json");
  EXPECT_NE(ParseErrorOf([&] {
              ParseCocoDetections(R"([{"image_id": 2, "category_id": 1, "bbox": [0, 0, 1, 1],
                "score": 1}])",
                                  "det.json", gt);
            }).find("det.json: field [0].image_id: image 2 is not in the ground truth gt.json"),
            std::string::npos);
  EXPECT_EQ(ParseErrorOf([&] {
              ParseCocoDetections(R"([{"image_id": 1, "category_id": 1, "bbox": [0, 0, 1, 1]}])",
                                  "det.json", gt);
            }),
            "det.json: field [0].score: missing");
  EXPECT_EQ(ParseErrorOf([&] { ParseCocoDetections(R"({"image_id": 1})", "det.json", gt); }),
            "det.json: a COCO results file is a JSON array of {image_id, category_id, bbox, "
            "score}");
  EXPECT_EQ(ParseErrorOf([&] {
              ParseCocoDetections(R"([{"image_id": 1, "category_id": 1, "bbox": [0, 0, 1, 1],
                "score": 1}, 5])",
                                  "det.json", gt);
            }),
            "det.json: field [1]: expected an object, got 5");
  EXPECT_EQ(ParseErrorOf([] { ParseCocoGroundTruth(R"({"categories": []})", "gt.json"); }),
            "gt.json: field images: missing");
  EXPECT_EQ(
      ParseErrorOf([] { ParseCocoGroundTruth(R"({"images": {}, "categories": []})", "gt.json"); }),
      "gt.json: field images: expected an array, got an object");
  EXPECT_EQ(ParseErrorOf([] { ParseCocoGroundTruth("[]", "gt.json"); }),
            "gt.json: a COCO ground-truth file is a JSON object");
}

// fuzz/corpus/coco (fuzz/coco_fuzzer.cc): the first byte chooses the file, even a ground truth
// (evaluated with one detection per annotation), odd a results file (read against a fixed ground
// truth). Each input parses or throws ParseError, and what parses evaluates to probabilities.
TEST(CocoTest, FuzzCorpusInputsParseOrThrowParseError) {
  const std::vector<std::filesystem::path> files = FuzzCorpusFiles("coco");
  ASSERT_GE(files.size(), 6u) << "the coco corpus is missing";
  const CocoGroundTruth fixed = OneCategory(
      {1, 2, 3}, {Box(1, 1, {10, 10, 40, 30}), Box(2, 2, {0, 0, 200, 150}, /*crowd=*/true)});
  int parsed = 0, rejected = 0;
  for (const std::filesystem::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string bytes = ReadFile(path);
    ASSERT_FALSE(bytes.empty());
    const std::string text = bytes.substr(1);
    try {
      CocoGroundTruth gt = fixed;
      std::vector<CocoDetection> dets;
      if (bytes[0] % 2 == 0) {
        gt = ParseCocoGroundTruth(text, "gt.json");
        for (const CocoAnnotation& a : gt.annotations) {
          if (std::binary_search(gt.image_ids.begin(), gt.image_ids.end(), a.image_id)) {
            dets.push_back({a.image_id, a.category_id, a.bbox, 1.0});
          }
        }
      } else {
        dets = ParseCocoDetections(text, "det.json", fixed);
      }
      ++parsed;
      const CocoEvalResult r = EvaluateCoco(gt, dets, CocoEvalOptions());
      for (const double v : r.stats) EXPECT_TRUE(v == -1 || (v >= 0 && v <= 1)) << v;
    } catch (const ParseError&) {
      ++rejected;
    }
  }
  EXPECT_GT(parsed, 0);
  EXPECT_GT(rejected, 0);
}

// The simdjson reader and the nlohmann one read the same detections from every file the first
// accepts, and where it does not the second decides: random results files with numbers in every
// JSON form (integers, fractions, exponents, negative, large), extra keys holding anything, keys
// in any order, and now and then a defect (a missing or repeated field, a float id, a bbox of 3).
TEST(CocoTest, FastAndNamingReadersAgree) {
  CocoGroundTruth gt;
  gt.source = "gt";
  gt.image_ids = {1, 2, 3, 900719925474099};
  std::mt19937 rng(21);
  std::uniform_int_distribution<int> pick(0, 99);
  auto number = [&]() -> std::string {
    switch (pick(rng) % 7) {
      case 0:
        return std::to_string(pick(rng));
      case 1:
        return fmt::format("{}", pick(rng) / 7.0);
      case 2:
        return fmt::format("{:.17g}", std::uniform_real_distribution<double>(0, 1e4)(rng));
      case 3:
        return fmt::format("{}e-{}", pick(rng), pick(rng) % 9);
      case 4:
        return fmt::format("-{}.{}E+{}", pick(rng), pick(rng), pick(rng) % 3);
      case 5:
        return "0.1000000000000000055511151231257827021181583404541015625";
      default:
        return "18446744073709551615";  // above int64: a double in both readers
    }
  };
  int fast = 0, defects = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string text = "[";
    bool defect = false;
    const int n = pick(rng) % 6;
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> fields = {
          fmt::format("\"image_id\": {}", gt.image_ids[pick(rng) % 4]),
          fmt::format("\"category_id\": {}", pick(rng) % 5),
          fmt::format("\"bbox\": [{}, {}, {}, {}]", number(), number(), number(), number()),
          fmt::format("\"score\": {}", number()),
          "\"segmentation\": {\"counts\": [1, 2, {\"x\": null}], \"size\": \"\\u00e9\"}",
          "\"id\": 7"};
      if (pick(rng) < 8) {
        defect = true;
        switch (pick(rng) % 4) {
          case 0:
            fields.erase(fields.begin() + pick(rng) % 4);
            break;
          case 1:
            fields.push_back(fields[pick(rng) % 4]);
            break;
          case 2:
            fields[0] = "\"image_id\": 1.0";
            break;
          default:
            fields[2] = "\"bbox\": [0, 0, 1]";
        }
      }
      std::shuffle(fields.begin(), fields.end(), rng);
      text += fmt::format("{}{{{}}}", i ? ", " : "", fmt::join(fields, ", "));
    }
    text += "]";
    defects += defect;
    std::vector<CocoDetection> a, b;
    bool a_threw = false, b_threw = false;
    try {
      a = ParseCocoDetections(text, "det", gt);
    } catch (const ParseError&) {
      a_threw = true;
    }
    try {
      b = ParseCocoDetectionsNamingErrors(text, "det", gt);
    } catch (const ParseError&) {
      b_threw = true;
    }
    ASSERT_EQ(a_threw, b_threw) << text;
    ASSERT_EQ(a.size(), b.size()) << text;
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].image_id, b[i].image_id) << text;
      ASSERT_EQ(a[i].category_id, b[i].category_id) << text;
      ASSERT_EQ(a[i].bbox.x, b[i].bbox.x) << text;
      ASSERT_EQ(a[i].bbox.y, b[i].bbox.y) << text;
      ASSERT_EQ(a[i].bbox.width, b[i].bbox.width) << text;
      ASSERT_EQ(a[i].bbox.height, b[i].bbox.height) << text;
      ASSERT_EQ(a[i].score, b[i].score) << text;
    }
    fast += !defect && !a_threw;
  }
  EXPECT_GT(fast, 100);
  EXPECT_GT(defects, 20);
}

// ReadCocoDetections reads a results file in blocks, cutting the top array between elements. At
// every block size (1 byte: every element cut everywhere), its detections, its refusals and its
// hash are those of the whole-file reader: random files with whitespace anywhere, strings in
// extra keys holding commas, brackets, braces, quotes and backslashes, and now and then a defect
// of the array itself (a comma too many or missing, text after it, no closing bracket).
TEST(CocoTest, BlockReaderAgreesWithTheWholeFileReader) {
  TestTempDir dir;
  CocoGroundTruth gt;
  gt.source = "gt";
  gt.image_ids = {1, 2, 3};
  std::mt19937 rng(38);
  std::uniform_int_distribution<int> pick(0, 99);
  auto space = [&]() -> std::string {
    constexpr std::array<const char*, 5> kSpaces = {"", "", " ", "\n  ", "\t\r\n"};
    return kSpaces[pick(rng) % kSpaces.size()];
  };
  auto tricky_string = [&]() -> std::string {
    // Some hold "}," (a wrong guess of the split: the scanner decides), one behind an escaped
    // quote.
    constexpr std::array<const char*, 9> kStrings = {
        R"("a,b")",           R"("]}{[")",      R"("say \"hi\", ok")",
        R"("back\\")",        R"("q\"],[{\"")", R"("\u005d,")",
        R"("x}, {\"y\": 1")", R"("\"},\"")",    R"("")"};
    return kStrings[pick(rng) % kStrings.size()];
  };
  int streamed_count = 0, refused_count = 0, defects = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::string text = space() + "[" + space();
    const int n = pick(rng) % 5;
    for (int i = 0; i < n; ++i) {
      std::vector<std::string> fields = {
          fmt::format("\"image_id\":{}{}", space(), 1 + pick(rng) % 3),
          fmt::format("\"category_id\": {}", pick(rng) % 4),
          fmt::format("\"bbox\": [{}, {},{}{}, {}]", pick(rng), pick(rng) / 8.0, space(), pick(rng),
                      pick(rng) + 0.5),
          fmt::format("\"score\" :{}", pick(rng) / 100.0),
          fmt::format("\"note\": {}", tricky_string())};
      std::shuffle(fields.begin(), fields.end(), rng);
      if (i > 0) text += space() + "," + space();
      text += fmt::format("{{{}{}}}", space(), fmt::join(fields, fmt::format(",{}", space())));
    }
    text += space() + "]" + space();
    bool defect = false;
    if (pick(rng) < 15) {
      defect = true;
      switch (pick(rng) % 6) {
        case 0:  // a trailing comma
          text.insert(text.rfind(']'), ",");
          break;
        case 1:  // a leading comma
          text.insert(text.find('[') + 1, ",");
          break;
        case 2:  // two commas, or one where none belongs
          text.insert(text.find('}') == std::string::npos ? text.size() - 1 : text.find('}') + 1,
                      ",,");
          break;
        case 3:  // text after the array
          text += "x";
          break;
        case 4:  // no closing bracket
          text.erase(text.rfind(']'));
          break;
        default:  // nothing at all, or whitespace only
          text = space();
      }
    }
    defects += defect;
    const std::filesystem::path path = dir.path() / "det.json";
    WriteFileAtomically(path, text);
    std::vector<CocoDetection> want;
    bool want_threw = false;
    try {
      want = ParseCocoDetectionsNamingErrors(text, path.string(), gt);
    } catch (const ParseError&) {
      want_threw = true;
    }
    for (const size_t block :
         {size_t{1}, size_t{2}, size_t{5}, size_t{16}, size_t{64}, kCocoReadBlockBytes}) {
      SCOPED_TRACE(fmt::format("block {}, text {}", block, text));
      std::vector<CocoDetection> got;
      bool got_threw = false, streamed = false;
      uint64_t hash = 12345;
      try {
        got = ReadCocoDetectionsInBlocks(path, gt, block, &hash, &streamed);
      } catch (const ParseError&) {
        got_threw = true;
      }
      ASSERT_EQ(got_threw, want_threw);
      // Every file without a defect is read by the fast path; a defect never is.
      EXPECT_EQ(streamed, !defect);
      ASSERT_EQ(got.size(), want.size());
      for (size_t i = 0; i < got.size(); ++i) {
        EXPECT_EQ(got[i].image_id, want[i].image_id);
        EXPECT_EQ(got[i].category_id, want[i].category_id);
        EXPECT_EQ(got[i].bbox.x, want[i].bbox.x);
        EXPECT_EQ(got[i].bbox.width, want[i].bbox.width);
        EXPECT_EQ(got[i].bbox.height, want[i].bbox.height);
        EXPECT_EQ(got[i].score, want[i].score);
      }
      if (!got_threw) {
        EXPECT_EQ(hash, Fnv1a64(text, 12345));
      }
      streamed_count += streamed;
      refused_count += !streamed;
    }
  }
  EXPECT_GT(streamed_count, 600);
  EXPECT_GT(defects, 15);
  EXPECT_GT(refused_count, 6 * 15);
}

// The scanner by hand: cuts only between the top array's elements, never inside strings (escaped
// quotes included) or nested values; the top array's closing bracket ends it.
TEST(CocoTest, ArrayScannerByHand) {
  const std::string text = R"([{"a":"x,\"]"},[1,2],"\\",3] ,)";
  CocoArrayScanner scanner;
  size_t cut = 0;
  const size_t close = scanner.Scan(text.data(), 1, text.size(), &cut);
  EXPECT_EQ(close, text.rfind(']'));
  EXPECT_EQ(cut, text.rfind(",3"));
  // Fed byte by byte, the same.
  CocoArrayScanner bytes;
  size_t bytes_cut = 0, bytes_close = CocoArrayScanner::kNoClose;
  for (size_t i = 1; i < text.size() && bytes_close == CocoArrayScanner::kNoClose; ++i) {
    bytes_close = bytes.Scan(text.data(), i, i + 1, &bytes_cut);
  }
  EXPECT_EQ(bytes_close, close);
  EXPECT_EQ(bytes_cut, cut);
}

// accumulate()'s arithmetic, transcribed from pycocotools line by line: cumulative counts,
// rc and pr at every detection, the envelope, searchsorted (side 'left').
void NumpyCurve(const std::vector<uint8_t>& flags, const std::vector<double>& scores, int64_t npig,
                const std::vector<double>& thresholds, double* recall,
                std::vector<double>* precision, std::vector<double>* score_at) {
  const size_t nd = flags.size();
  std::vector<double> rc(nd), pr(nd);
  double tp = 0, fp = 0;
  for (size_t j = 0; j < nd; ++j) {
    const bool ignored = flags[j] & kCocoIgnored, matched = flags[j] & kCocoMatched;
    tp += !ignored && matched;
    fp += !ignored && !matched;
    rc[j] = tp / static_cast<double>(npig);
    pr[j] = tp / (fp + tp + std::numeric_limits<double>::epsilon());
  }
  *recall = nd > 0 ? rc.back() : 0.0;
  for (size_t j = nd; j-- > 1;) pr[j - 1] = std::max(pr[j - 1], pr[j]);
  precision->assign(thresholds.size(), 0.0);
  score_at->assign(thresholds.size(), 0.0);
  for (size_t r = 0; r < thresholds.size(); ++r) {
    const size_t at = std::lower_bound(rc.begin(), rc.end(), thresholds[r]) - rc.begin();
    if (at >= nd) break;
    (*precision)[r] = pr[at];
    (*score_at)[r] = scores[at];
  }
}

// The curve read at the true positives alone equals numpy's over every detection, bit for bit:
// random sequences of true positives, false positives and ignored detections (matched ones too),
// npig from below to above the true positives' count, empty sequences, COCO's 101 thresholds
// and uneven ones.
TEST(CocoTest, CurveAtTruePositivesEqualsNumpysOverEveryDetection) {
  std::mt19937 rng(101);
  std::uniform_int_distribution<int> pick(0, 99);
  const std::vector<double> coco = CocoRecallThresholds();
  const std::vector<double> uneven = {0.0, 1e-9, 0.3333333333333333, 0.5, 0.999, 1.0};
  CocoCurveScratch scratch;
  for (int trial = 0; trial < 3000; ++trial) {
    const size_t nd = trial % 50 == 0 ? 0 : pick(rng) % 40;
    std::vector<uint8_t> flags(nd);
    std::vector<double> scores(nd);
    int64_t tps = 0;
    for (size_t j = 0; j < nd; ++j) {
      const int roll = pick(rng);
      flags[j] = roll < 40   ? kCocoMatched
                 : roll < 80 ? 0
                 : roll < 90 ? kCocoIgnored
                             : kCocoIgnored | kCocoMatched;
      tps += flags[j] == kCocoMatched;
      scores[j] = 1.0 - static_cast<double>(j) / 64;
    }
    const int64_t npig = std::max<int64_t>(1, tps + pick(rng) % 7 - 2);
    for (const std::vector<double>* thresholds : {&coco, &uneven}) {
      SCOPED_TRACE(fmt::format("trial {}, nd {}, npig {}", trial, nd, npig));
      double want_recall = 0;
      std::vector<double> want_precision, want_scores;
      NumpyCurve(flags, scores, npig, *thresholds, &want_recall, &want_precision, &want_scores);
      const size_t R = thresholds->size();
      std::vector<double> precision(2 * R, -7), score_at(2 * R, -7);
      double recall = -7;
      CocoAccumulateCurve(flags.data(), scores.data(), nd, npig, *thresholds, &scratch, &recall,
                          precision.data(), score_at.data(), 2);
      ASSERT_EQ(recall, want_recall);
      for (size_t r = 0; r < R; ++r) {
        ASSERT_EQ(precision[2 * r], want_precision[r]) << "threshold " << r;
        ASSERT_EQ(score_at[2 * r], want_scores[r]) << "threshold " << r;
        ASSERT_EQ(precision[2 * r + 1], -7);  // the stride's gaps untouched
      }
    }
  }
}

// Stable area ranges by hand: one detection (36 x 36 at the origin) overlaps a small box A (30 x
// 30: IoU 0.694) and, more, a medium one B (40 x 40: IoU 0.81). Range "all" matches it
// to B. pycocotools matches range "small" on its own, B ignored there, and finds A with it: a TP
// that "all" does not have. Counted from "all"'s matching, the pair belongs to medium; in small it
// drops out and A is missed. Medium and all are the same under both.
TEST(CocoTest, StableAreaRangesCountFromTheMatchingOfAll) {
  const CocoGroundTruth gt =
      OneCategory({1}, {Box(1, 1, {0, 0, 30, 30}), Box(2, 1, {0, 0, 40, 40})});
  const std::vector<CocoDetection> dets = {Det(1, {0, 0, 36, 36}, 0.9)};
  CocoEvalOptions pycocotools, stable;
  stable.stable_area_ranges = true;
  const CocoEvalResult p = EvaluateCoco(gt, dets, pycocotools);
  const CocoEvalResult s = EvaluateCoco(gt, dets, stable);
  constexpr int kAll = 0, kSmall = 1, kMedium = 2, kLast = 2;
  // IoU 0.5 (t 0): small's recall 1 under pycocotools, 0 stable.
  EXPECT_EQ(p.recall[p.RecallIndex(0, 0, kSmall, kLast)], 1.0);
  EXPECT_EQ(s.recall[s.RecallIndex(0, 0, kSmall, kLast)], 0.0);
  EXPECT_DOUBLE_EQ(p.precision[p.PrecisionIndex(0, 0, 0, kSmall, kLast)], 1.0);  // 1 / (1 + eps)
  EXPECT_EQ(s.precision[s.PrecisionIndex(0, 0, 0, kSmall, kLast)], 0.0);
  for (const int a : {kAll, kMedium}) {
    for (size_t t = 0; t < p.options.iou_thresholds.size(); ++t) {
      const int ti = static_cast<int>(t);
      EXPECT_EQ(p.recall[p.RecallIndex(ti, 0, a, kLast)], s.recall[s.RecallIndex(ti, 0, a, kLast)])
          << "area " << a << " threshold " << t;
    }
  }
  // all: B found up to IoU 0.80 (t 0..6), A never: recall 1/2 there.
  EXPECT_EQ(s.recall[s.RecallIndex(0, 0, kAll, kLast)], 0.5);
  EXPECT_EQ(s.recall[s.RecallIndex(0, 0, kMedium, kLast)], 1.0);
  EXPECT_LT(s.stats[kApSmall], p.stats[kApSmall]);
  EXPECT_EQ(s.stats[kApMedium], p.stats[kApMedium]);
  EXPECT_EQ(s.stats[kAp], p.stats[kAp]);
  // Only with the greedy matcher, and only with a range "all".
  stable.matcher = CocoMatcher::kOptimal;
  EXPECT_THROW(stable.Check(), std::invalid_argument);
  stable = CocoEvalOptions();
  stable.stable_area_ranges = true;
  stable.area_ranges.erase(stable.area_ranges.begin());
  EXPECT_THROW(stable.Check(), std::invalid_argument);
}

// The stable property on a random set with crowds, duplicates and every area range: in every
// range, a detection is a TP only where it is one in "all", a FP only where it is one in "all";
// the ranges' TPs at each threshold add up to all's (every valid box is in one of small, medium,
// large, and its pair goes with it); the cells' counts agree with the flags; and range "all" is
// pycocotools' own.
TEST(CocoTest, StableAreaRangesHoldNoErrorThatAllHasNot) {
  const RandomCocoSet set = MakeRandomCocoSet();
  CocoEvalOptions stable, pycocotools;
  stable.stable_area_ranges = true;
  stable.score_metrics = pycocotools.score_metrics = true;
  std::vector<CocoCategoryDetections> categories;
  const CocoEvalResult s = EvaluateCocoKeepingDetections(set.gt, set.dets, stable, &categories);
  const CocoEvalResult p = EvaluateCoco(set.gt, set.dets, pycocotools);
  const size_t T = s.options.iou_thresholds.size(), A = s.options.area_ranges.size();
  int differ = 0;
  for (size_t k = 0; k < categories.size(); ++k) {
    const CocoCategoryDetections& c = categories[k];
    for (size_t t = 0; t < T; ++t) {
      int tp_all = 0, tp_ranges = 0;
      for (size_t d = 0; d < c.score.size(); ++d) {
        const uint8_t all = c.flags[(d * A + 0) * T + t];
        tp_all += all == kCocoMatched;
        for (size_t a = 1; a < A; ++a) {
          const uint8_t f = c.flags[(d * A + a) * T + t];
          if (f == kCocoMatched) {
            EXPECT_EQ(all, kCocoMatched);
          }
          if (f == 0) {
            EXPECT_EQ(all, 0);
          }
          tp_ranges += f == kCocoMatched;
        }
      }
      EXPECT_EQ(tp_ranges, tp_all) << "category " << k << " threshold " << t;
      for (size_t a = 0; a < A; ++a) {
        const CocoCell& cell =
            s.cells[s.CellIndex(static_cast<int>(t), static_cast<int>(k), static_cast<int>(a))];
        const CocoCell& whole = s.cells[s.CellIndex(static_cast<int>(t), static_cast<int>(k), 0)];
        EXPECT_LE(cell.at_threshold.fp, whole.at_threshold.fp);
        EXPECT_LE(cell.at_threshold.tp, whole.at_threshold.tp);
        EXPECT_LE(cell.at_threshold.fn, whole.at_threshold.fn);
      }
    }
  }
  for (size_t i = 0; i < s.recall.size(); ++i) differ += s.recall[i] != p.recall[i];
  EXPECT_GT(differ, 0);  // the random set has pairs that cross a range's edge
  for (size_t t = 0; t < T; ++t) {
    for (size_t k = 0; k < categories.size(); ++k) {
      const int ti = static_cast<int>(t), ki = static_cast<int>(k);
      EXPECT_EQ(s.recall[s.RecallIndex(ti, ki, 0, 2)], p.recall[p.RecallIndex(ti, ki, 0, 2)]);
    }
  }
}

TEST(CocoTest, OptionsCheck) {
  EXPECT_NO_THROW(CocoEvalOptions().Check());
  CocoEvalOptions o;
  o.max_dets = {10, 10, 100};
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CocoEvalOptions();
  o.max_dets = {1, 100};
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CocoEvalOptions();
  o.iou_thresholds = {0.5, 1.5};
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CocoEvalOptions();
  o.recall_thresholds = {0.5, 0.2};
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CocoEvalOptions();
  o.area_ranges.push_back({"small", 0, 1});
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CocoEvalOptions();
  o.area_ranges[1].min_area = 5000;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
