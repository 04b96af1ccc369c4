#include "stereodet/eval/breakdown.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

using testing_objects::CarModerate2D;
using testing_objects::Det;
using testing_objects::Label;

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(BreakdownTest, ParsesAxesAndEdgesAndSaysWhatIsWrong) {
  const BreakdownOptions d = ParseBreakdown("distance=0,30,50,inf");
  EXPECT_EQ(d.axis, BreakdownAxis::kDistance);
  EXPECT_EQ(d.edges, (std::vector<double>{0, 30, 50, kInf}));
  EXPECT_EQ(d.num_bins(), 3);
  EXPECT_EQ(BreakdownText(d), "distance=0,30,50,inf");
  EXPECT_EQ(BreakdownText(ParseBreakdown(" height = -inf, 40 ,1e3")), "height=-inf,40,1000");
  EXPECT_EQ(ParseBreakdown("occlusion=0,1,2,4").axis, BreakdownAxis::kOcclusion);
  EXPECT_EQ(BreakdownBinName(50, kInf), "[50, inf)");
  EXPECT_EQ(BreakdownBinName(0.5, 1), "[0.5, 1)");
  for (const char* bad : {"distance", "speed=0,1", "distance=0", "distance=30,0", "distance=0,0,1",
                          "distance=0,inf,100", "distance=inf,0", "distance=0,x", "distance=0,nan",
                          "distance=0,,1"}) {
    SCOPED_TRACE(bad);
    EXPECT_THROW(ParseBreakdown(bad), std::invalid_argument);
  }
  try {
    ParseBreakdown("distance=30,0");
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("edges must increase, got 30 then 0"), std::string::npos)
        << e.what();
  }
}

TEST(BreakdownTest, ValuesOfLabelsAndDetections) {
  Object label = Label("Car", {100, 150, 300, 200}, 0.2, 1);
  label.box3d.location.z() = 42.0;
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kDistance, label, true), 42.0);
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kHeight, label, true), 50.0);
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kOcclusion, label, true), 1.0);
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kTruncation, label, true), 0.2);
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kColumn, label, true), 200.0);
  Object det = Det("Car", {100, 150, 300, 200}, 0.9);
  det.box3d.location.z() = 41.0;
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kDistance, det, false), 41.0);
  EXPECT_FALSE(BreakdownValue(BreakdownAxis::kOcclusion, det, false).has_value());
  EXPECT_FALSE(BreakdownValue(BreakdownAxis::kTruncation, det, false).has_value());
  det.SetNot3DEstimated();  // a 2D detector's line: location -1000
  EXPECT_FALSE(BreakdownValue(BreakdownAxis::kDistance, det, false).has_value());
  EXPECT_EQ(BreakdownValue(BreakdownAxis::kHeight, det, false), 50.0);
}

// Three cars at 10, 40 and 60 m; the first found by a 3D detection at 12 m, the second by a 2D
// detection, the third missed; a false positive at 35 m and one without a distance. By hand, per
// bin of distance=0,30,50,inf: [0, 30): the 10 m pair, the distance-less FP; [30, 50): the 40 m
// pair (its label decides), both FPs; [50, inf): the 60 m miss, the distance-less FP.
// Random frames with scores of two decimals (ties across frames).
std::vector<EvalFrame> ScoredRandomFrames(int num_frames, int seed) {
  RandomFramesOptions ro;
  ro.num_frames = num_frames;
  ro.seed = seed;
  ro.score_decimals = 2;
  return RandomFrames(ro);
}

std::vector<EvalFrame> ThreeDistancesFrame() {
  EvalFrame frame;
  frame.id = "000000";
  const double zs[] = {10, 40, 60};
  for (int k = 0; k < 3; ++k) {
    Object label = Label("Car", {100.0 + 200 * k, 150, 250.0 + 200 * k, 200});
    label.box3d.location.z() = zs[k];
    frame.labels.push_back(label);
  }
  Object near = Det("Car", {100, 150, 250, 200}, 0.9);
  near.box3d.location.z() = 12;
  Object middle = Det("Car", {300, 150, 450, 200}, 0.8);
  middle.SetNot3DEstimated();
  Object fp_35 = Det("Car", {800, 150, 950, 200}, 0.7);
  fp_35.box3d.location.z() = 35;
  Object fp_2d = Det("Car", {1000, 150, 1150, 200}, 0.6);
  fp_2d.SetNot3DEstimated();
  frame.detections = {near, middle, fp_35, fp_2d};
  return {frame};
}

TEST(BreakdownTest, ByHandPairsFollowTheirLabelsAndUnplacedFalsePositivesCountEverywhere) {
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    SCOPED_TRACE(MatcherName(matcher));
    EvalOptions options = CarModerate2D(matcher);
    options.breakdowns = {ParseBreakdown("distance=0,30,50,inf")};
    const EvalResult result = Evaluate(ThreeDistancesFrame(), options);
    const ClassResult& cell = result.results.at(0);
    EXPECT_EQ(cell.at_threshold.tp, 2);
    EXPECT_EQ(cell.at_threshold.fp, 2);
    EXPECT_EQ(cell.at_threshold.fn, 1);
    ASSERT_EQ(cell.breakdown.size(), 3u);
    const int64_t expected[3][4] = {{1, 1, 1, 0}, {1, 1, 2, 0}, {1, 0, 1, 1}};  // labels TP FP FN
    for (int b = 0; b < 3; ++b) {
      SCOPED_TRACE(b);
      const BreakdownBin& bin = cell.breakdown[b];
      EXPECT_EQ(bin.axis, BreakdownAxis::kDistance);
      EXPECT_EQ(bin.lower, options.breakdowns[0].edges[b]);
      EXPECT_EQ(bin.upper, options.breakdowns[0].edges[b + 1]);
      EXPECT_EQ(bin.num_valid_labels, expected[b][0]);
      EXPECT_EQ(bin.at_threshold.tp, expected[b][1]);
      EXPECT_EQ(bin.at_threshold.fp, expected[b][2]);
      EXPECT_EQ(bin.at_threshold.fn, expected[b][3]);
    }
    // [0, 30): its one label found at the top score: AP 100 for the exact matchers. The KITTI
    // matcher's curve has the whole cell's thresholds, the scores of its 2 TPs: precision 1 in
    // slots 0 and 1 of 41, so AP_R40 = 1 / 40 (the small-sample cap, metrics.md). [50, inf):
    // nothing found: 0.
    EXPECT_DOUBLE_EQ(cell.breakdown[0].curve.ap_r40, matcher == Matcher::kKitti ? 2.5 : 100.0);
    EXPECT_DOUBLE_EQ(cell.breakdown[2].curve.ap_r40, 0.0);
    // Brier over labels: [0, 30) one TP at 0.9: 0.01; [50, inf) one miss: 1.
    EXPECT_NEAR(cell.breakdown[0].brier.over_labels, 0.01, 1e-12);
    EXPECT_DOUBLE_EQ(cell.breakdown[2].brier.over_labels, 1.0);
    // Over detections in [30, 50): the 0.8 TP, the FPs at 0.7 and 0.6.
    EXPECT_NEAR(cell.breakdown[1].brier.over_detections, (0.04 + 0.49 + 0.36) / 3, 1e-12);
    // Calibration per bin, the same detections: [30, 50) holds the 0.8 TP (bin 8) and the FPs at
    // 0.7 and 0.6 (bins 7 and 6): ECE = (0.2 + 0.7 + 0.6) / 3; [50, inf) only the distance-less
    // FP at 0.6: ECE 0.6.
    EXPECT_EQ(cell.breakdown[1].calibration.num_detections, 3);
    EXPECT_NEAR(cell.breakdown[1].calibration.ece, (0.2 + 0.7 + 0.6) / 3, 1e-12);
    EXPECT_EQ(cell.breakdown[1].calibration.bins[8].tp_fraction, 1.0);
    EXPECT_EQ(cell.breakdown[2].calibration.num_detections, 1);
    EXPECT_NEAR(cell.breakdown[2].calibration.ece, 0.6, 1e-12);
  }
}

// The naive per-bin recomputation beside the stable one, by hand on the same frame: a bin's own
// evaluation strikes the labels and detections outside it before matching, so the 2D-only
// detection of the 40 m car (no distance: kept in every bin) is a FP in [0, 30) and [50, inf),
// where its label is struck, instead of belonging to its label's bin.
TEST(BreakdownTest, NaiveBinsStrikeBeforeMatchingByHand) {
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    SCOPED_TRACE(MatcherName(matcher));
    EvalOptions options = CarModerate2D(matcher);
    options.breakdowns = {ParseBreakdown("distance=0,30,50,inf")};
    options.breakdown_naive = true;
    const EvalResult result = Evaluate(ThreeDistancesFrame(), options);
    const ClassResult& cell = result.results.at(0);
    ASSERT_EQ(cell.breakdown.size(), 3u);
    const int64_t stable[3][3] = {{1, 1, 0}, {1, 2, 0}, {0, 1, 1}};  // TP FP FN
    const int64_t naive[3][3] = {{1, 2, 0}, {1, 2, 0}, {0, 2, 1}};
    for (int b = 0; b < 3; ++b) {
      SCOPED_TRACE(b);
      const BreakdownBin& bin = cell.breakdown[b];
      EXPECT_EQ(bin.at_threshold.tp, stable[b][0]);
      EXPECT_EQ(bin.at_threshold.fp, stable[b][1]);
      EXPECT_EQ(bin.at_threshold.fn, stable[b][2]);
      ASSERT_TRUE(bin.naive.has_value());
      EXPECT_EQ(bin.naive->num_valid_labels, 1);
      EXPECT_EQ(bin.naive->at_threshold.tp, naive[b][0]);
      EXPECT_EQ(bin.naive->at_threshold.fp, naive[b][1]);
      EXPECT_EQ(bin.naive->at_threshold.fn, naive[b][2]);
    }
    // [0, 30) on its own: the 0.9 TP first, then the two FPs: AP 100 for the exact matchers. The
    // KITTI matcher takes its thresholds from the bin's own single TP: one threshold, slot 0 of
    // 41, which AP_R40 leaves out: 0 (the devkit's small-sample arithmetic; the stable bin, at the
    // cell's two thresholds, had 2.5). [50, inf): nothing found.
    EXPECT_DOUBLE_EQ(cell.breakdown[0].naive->curve.ap_r40,
                     matcher == Matcher::kKitti ? 0.0 : 100.0);
    EXPECT_DOUBLE_EQ(cell.breakdown[2].naive->curve.ap_r40, 0.0);
  }
  // Without the option, no naive numbers.
  EvalOptions options = CarModerate2D(Matcher::kOptimal);
  options.breakdowns = {ParseBreakdown("distance=0,30,50,inf")};
  EXPECT_FALSE(Evaluate(ThreeDistancesFrame(), options).results.at(0).breakdown[0].naive);
}

// A bin that holds every value, evaluated naively, is the whole cell evaluated: same counts and
// AP as the cell, for every matcher, on random frames.
TEST(BreakdownTest, NaiveBinOfEverythingIsTheCell) {
  const std::vector<EvalFrame> frames = ScoredRandomFrames(30, 11);
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    SCOPED_TRACE(MatcherName(matcher));
    EvalOptions options;
    options.matcher = matcher;
    options.score_threshold = 0.3;
    options.breakdowns = {ParseBreakdown("height=-inf,inf")};
    options.breakdown_naive = true;
    int checked = 0;
    for (const ClassResult& cell : Evaluate(frames, options).results) {
      if (!cell.evaluated) continue;
      const BreakdownBin::Naive& all = *cell.breakdown.at(0).naive;
      EXPECT_EQ(all.num_valid_labels, cell.num_valid_labels);
      EXPECT_EQ(all.at_threshold.tp, cell.at_threshold.tp);
      EXPECT_EQ(all.at_threshold.fp, cell.at_threshold.fp);
      EXPECT_EQ(all.at_threshold.fn, cell.at_threshold.fn);
      if (cell.num_valid_labels > 0) {
        EXPECT_NEAR(all.curve.ap_r40, cell.ap_r40, 1e-9);
      }
      ++checked;
    }
    EXPECT_GT(checked, 10);
  }
}

// Property, on random frames for every matcher: the bins of an axis that covers every value
// partition the TPs and FNs of the whole cell and hold no more FPs than it; a single bin
// (-inf, inf) is the whole cell, curve and Brier included.
TEST(BreakdownTest, BinsPartitionTheCellAndOneBinOfEverythingIsTheCell) {
  const std::vector<EvalFrame> frames = ScoredRandomFrames(40, 7);
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    SCOPED_TRACE(MatcherName(matcher));
    EvalOptions options;
    options.matcher = matcher;
    options.score_threshold = 0.3;
    options.breakdowns = {ParseBreakdown("distance=-inf,15,30,inf"),
                          ParseBreakdown("height=-inf,inf"), ParseBreakdown("column=-inf,600,inf"),
                          ParseBreakdown("occlusion=-inf,1,2,inf")};
    const EvalResult result = Evaluate(frames, options);
    int checked = 0;
    for (const ClassResult& cell : result.results) {
      if (!cell.evaluated) continue;
      ASSERT_EQ(cell.breakdown.size(), 3u + 1u + 2u + 3u);
      for (const auto& [begin, end] : {std::pair{0, 3}, std::pair{4, 6}, std::pair{6, 9}}) {
        int64_t tp = 0, fn = 0, labels = 0;
        for (int b = begin; b < end; ++b) {
          const BreakdownBin& bin = cell.breakdown[b];
          tp += bin.at_threshold.tp;
          fn += bin.at_threshold.fn;
          labels += bin.num_valid_labels;
          EXPECT_LE(bin.at_threshold.fp, cell.at_threshold.fp);
        }
        EXPECT_EQ(tp, cell.at_threshold.tp);
        EXPECT_EQ(fn, cell.at_threshold.fn);
        EXPECT_EQ(labels, cell.num_valid_labels);
      }
      const BreakdownBin& all = cell.breakdown[3];  // height=-inf,inf
      EXPECT_EQ(all.num_valid_labels, cell.num_valid_labels);
      EXPECT_EQ(all.at_threshold.tp, cell.at_threshold.tp);
      EXPECT_EQ(all.at_threshold.fp, cell.at_threshold.fp);
      EXPECT_EQ(all.at_threshold.fn, cell.at_threshold.fn);
      EXPECT_NEAR(all.curve.ap_r40, cell.ap_r40, 1e-9);
      EXPECT_NEAR(all.curve.ap_r11, cell.ap_r11, 1e-9);
      if (std::isnan(cell.brier.over_labels)) {
        EXPECT_TRUE(std::isnan(all.brier.over_labels));
      } else {
        EXPECT_NEAR(all.brier.over_labels, cell.brier.over_labels, 1e-12);
        EXPECT_NEAR(all.brier.over_detections, cell.brier.over_detections, 1e-12);
      }
      // The bin of everything has the cell's reliability, ECE and LaECE.
      EXPECT_EQ(all.calibration.num_detections, cell.calibration.num_detections);
      if (!std::isnan(cell.calibration.ece)) {
        EXPECT_NEAR(all.calibration.ece, cell.calibration.ece, 1e-12);
        EXPECT_NEAR(all.calibration.laece, cell.calibration.laece, 1e-12);
      }
      // The distance bins' detections: each counted detection in exactly one bin, except a FP
      // without a distance, which is in every bin (so at least the cell's count).
      int64_t counted = 0;
      for (int b = 0; b < 3; ++b) counted += cell.breakdown[b].calibration.num_detections;
      EXPECT_GE(counted, cell.calibration.num_detections);
      ++checked;
    }
    EXPECT_GT(checked, 0);
  }
}

}  // namespace
}  // namespace stereodet
