#include "stereodet/eval/score_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/score_metrics_internal.h"
#include "stereodet/eval/test_objects.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

using testing_objects::Car;

// Brier three ways, by hand: one TP (s = 0.9), one FP (s = 0.4), one FN.
TEST(ScoreMetricsTest, BrierThreeWaysByHand) {
  EvalFrame f;
  Object l1, l2, d1, d2;
  l1.type = l2.type = d1.type = d2.type = "Car";
  l1.box = {0, 0, 100, 100};
  l2.box = {300, 0, 400, 100};
  d1.box = {0, 0, 100, 100};
  d1.score = 0.9;
  d2.box = {600, 0, 700, 100};
  d2.score = 0.4;
  f.labels = {l1, l2};
  f.detections = {d1, d2};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult result = Evaluate({f}, options);  // keeps the result alive
    const ClassResult& r = result.results.at(0);
    EXPECT_NEAR(r.brier.over_labels, (0.01 + 1.0) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_detections, (0.01 + 0.16) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_all, (0.01 + 0.16 + 1.0) / 3, 1e-12);
    // Reliability, 10 bins: 0.4 (FP) in bin 4, 0.9 (TP) in bin 9. ECE = (0.4 + 0.1) / 2.
    EXPECT_EQ(r.calibration.bins[4].count, 1);
    EXPECT_EQ(r.calibration.bins[9].tp_fraction, 1.0);
    EXPECT_NEAR(r.calibration.ece, 0.25, 1e-12);
  }
}

// LaECE by hand, through the evaluator: a TP whose box covers the top 60 % of its label (2D IoU
// 0.6; a match needs more than 0.5), score 0.9; a FP at 0.4; a TP fitting exactly (IoU 1) at 0.95.
// Bins of 0.1: bin 9 holds the two TPs (mean score 0.925, mean IoU 0.8, TP fraction 1), bin 4 the
// FP (0.4, IoU 0). LaECE = 2/3 |0.925 - 0.8| + 1/3 |0.4 - 0| = 0.0833 + 0.1333; ECE = 2/3 |0.925 -
// 1| + 1/3 |0.4 - 0| = 0.05 + 0.1333.
TEST(ScoreMetricsTest, LocalizationAwareEceByHand) {
  EvalFrame f;
  Object l1, l2, d1, d2, d3;
  l1.type = l2.type = d1.type = d2.type = d3.type = "Car";
  l1.box = {0, 0, 100, 100};
  l2.box = {300, 0, 400, 100};
  d1.box = {0, 0, 100, 60};
  d1.score = 0.9;
  d2.box = {600, 0, 700, 100};
  d2.score = 0.4;
  d3.box = {300, 0, 400, 100};
  d3.score = 0.95;
  f.labels = {l1, l2};
  f.detections = {d1, d2, d3};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.classes[0].min_overlap = {0.5, 0.5, 0.5};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kEasy};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult result = Evaluate({f}, options);
    const ClassResult& r = result.results.at(0);
    EXPECT_NEAR(r.calibration.bins[9].mean_iou, 0.8, 1e-12) << MatcherName(m);
    EXPECT_NEAR(r.calibration.bins[4].mean_iou, 0.0, 1e-12) << MatcherName(m);
    EXPECT_TRUE(std::isnan(r.calibration.bins[0].mean_iou));
    EXPECT_NEAR(r.calibration.laece, 2.0 / 3 * 0.125 + 0.4 / 3, 1e-12) << MatcherName(m);
    EXPECT_NEAR(r.calibration.ece, 2.0 / 3 * 0.075 + 0.4 / 3, 1e-12) << MatcherName(m);
  }
}

// D-ECE by hand: two detections of score 0.9 in a 1242 x 375 image, a TP (l1's, at the left) and a
// FP. In one joint bin their TP fraction is 1/2: D-ECE = |0.5 - 0.9| = 0.4 = ECE. A FP far to the
// right puts them in two bins of the centre's x: D-ECE = 1/2 |1 - 0.9| + 1/2 |0 - 0.9| = 0.5 > ECE:
// D-ECE sees that the scores are right for neither place. A box past the image's edge (centre x
// beyond 1242) is clamped into the last bin of x, as netcal does.
TEST(ScoreMetricsTest, DetectionEceByHand) {
  EvalFrame f;
  Object l1, d1, d2;
  l1.type = d1.type = d2.type = "Car";
  l1.box = {0, 100, 100, 200};
  d1.box = l1.box;
  d1.score = 0.9;
  d2.box = {10, 150, 110, 250};  // same bins as d1 (5 per feature): a FP beside it
  d2.score = 0.9;
  f.labels = {l1};
  f.detections = {d1, d2};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kEasy};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    EXPECT_NEAR(Evaluate({f}, options).results.at(0).calibration.dece, 0.4, 1e-12)
        << MatcherName(m);
  }
  f.detections[1].box = {1100, 100, 1200, 200};
  options.matcher = Matcher::kOptimal;
  CalibrationResult c = Evaluate({f}, options).results.at(0).calibration;
  EXPECT_NEAR(c.dece, 0.5, 1e-12);
  EXPECT_NEAR(c.ece, 0.4, 1e-12);
  EXPECT_EQ(c.dece_outside, 0);
  f.detections[1].box = {1200, 100, 1400, 200};
  c = Evaluate({f}, options).results.at(0).calibration;
  EXPECT_EQ(c.dece_outside, 1);
  EXPECT_NEAR(c.dece, 0.5, 1e-12);
  // One bin per box feature: D-ECE is ECE over the score's bins (5 here).
  options.dece.bins = {10, 1, 1, 1, 1};
  f.detections[1].box = {1100, 100, 1200, 200};
  c = Evaluate({f}, options).results.at(0).calibration;
  EXPECT_NEAR(c.dece, c.ece, 1e-12);
  options.dece.bins = {0, 1, 1, 1, 1};
  EXPECT_THROW(Evaluate({f}, options), std::invalid_argument);
}

// netcal's own D-ECE (ECE(bins, detection=True), revision 2a3db8d, run unmodified by
// scripts/dece_reference_cases.py) on five sets of 60 to 5000 detections and three bin layouts:
// tests/data/calibration/netcal_dece.csv. Some boxes reach past the image: clamped into the edge
// bins in both.
TEST(ScoreMetricsTest, DeceAgreesWithNetcal) {
  std::ifstream in(TestSourceDir() / "tests/data/calibration/netcal_dece.csv");
  ASSERT_TRUE(in);
  std::map<int, std::vector<std::pair<Box2D, std::pair<double, bool>>>> cases;
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> v;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(field);
    const int k = std::stoi(v.at(0));
    if (v.at(1) == "det") {
      const Box2D box{std::stod(v[2]), std::stod(v[3]), std::stod(v[4]), std::stod(v[5])};
      cases[k].push_back({box, {std::stod(v[6]), v[7] == "1"}});
      continue;
    }
    DeceOptions dece;
    for (int d = 0; d < 5; ++d) dece.bins[d] = std::stoi(v.at(2 + d));
    ScoreMetricsAccumulator acc(10, 5.0, 80.0);
    acc.EnableDece(dece);
    for (const auto& [box, st] : cases.at(k)) acc.AddDetectionTerm(st.first, st.second, 0.0, &box);
    EXPECT_NEAR(acc.Calibration().dece, std::stod(v.at(7)), 1e-12) << line;
    ++checked;
  }
  EXPECT_EQ(checked, 15);
}

// Brier over labels has a fixed support: one term per valid label whatever the detector did. Two
// detectors on the same two labels (l1 100 px tall, l2 30 px, both valid at Moderate): A finds l1
// (0.9) and misses l2; B finds l1 (0.9) and covers l2 with a 24 px detection, which Moderate
// ignores (< 25 px), so l2 is excused (neither TP nor FN). Both are scored over 2 label terms:
// ((1 - 0.9)^2 + 1) / 2 = 0.505. (Before, B's l2 dropped out: 1 term, 0.01.)
TEST(ScoreMetricsTest, BrierOverLabelsHasAFixedSupport) {
  const Object l1 = Car({0, 0, 100, 100}), l2 = Car({300, 0, 400, 30});
  EvalFrame a, b;
  a.labels = b.labels = {l1, l2};
  a.detections = {Car({0, 0, 100, 100}, 0.9), Car({600, 0, 700, 100}, 0.4)};
  b.detections = {Car({0, 0, 100, 100}, 0.9), Car({300, 0, 400, 24}, 0.7)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult ra = Evaluate({a}, options), rb = Evaluate({b}, options);
    const ClassResult &ca = ra.results.at(0), &cb = rb.results.at(0);
    EXPECT_EQ(cb.at_threshold.fn, 0) << MatcherName(m);  // l2 is excused, not missed
    EXPECT_EQ(ca.num_valid_labels, 2);
    EXPECT_EQ(ca.brier.num_label_terms, ca.num_valid_labels) << MatcherName(m);
    EXPECT_EQ(cb.brier.num_label_terms, cb.num_valid_labels) << MatcherName(m);
    EXPECT_NEAR(ca.brier.over_labels, 0.505, 1e-12) << MatcherName(m);
    EXPECT_NEAR(cb.brier.over_labels, 0.505, 1e-12) << MatcherName(m);
    // Over all: the label terms plus one s^2 per FP (A's 0.4; B has none).
    EXPECT_EQ(ca.brier.num_all_terms, 3);
    EXPECT_NEAR(ca.brier.over_all, (0.01 + 1.0 + 0.16) / 3, 1e-12);
    EXPECT_EQ(cb.brier.num_all_terms, 2);
    EXPECT_NEAR(cb.brier.over_all, 0.505, 1e-12);
  }
}

// Brier and ECE need probabilities. Logit scores (2.0 TP, -1.0 FP): left out (NaN) unless
// --score-transform sigmoid; AP, the curve and the operating point are the raw scores' either way.
TEST(ScoreMetricsTest, ScoresOutsideTheUnitIntervalLeaveBrierOutUnlessTransformed) {
  EvalFrame f;
  f.labels = {Car({0, 0, 100, 100}), Car({300, 0, 400, 100})};
  f.detections = {Car({0, 0, 100, 100}, 2.0), Car({600, 0, 700, 100}, -1.0),
                  Car({300, 0, 400, 100}, 40.0)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal}) {
    options.matcher = m;
    options.score_transform = ScoreTransform::kNone;
    const EvalResult raw = Evaluate({f}, options);
    EXPECT_FALSE(raw.probability_metrics);
    EXPECT_EQ(raw.scores.num_scores, 3);
    EXPECT_EQ(raw.scores.num_outside_unit, 3);
    EXPECT_EQ(raw.scores.min_score, -1.0);
    EXPECT_EQ(raw.scores.max_score, 40.0);
    options.score_transform = ScoreTransform::kSigmoid;
    const EvalResult sig = Evaluate({f}, options);
    EXPECT_TRUE(sig.probability_metrics);
    ASSERT_EQ(raw.results.size(), sig.results.size());
    for (size_t k = 0; k < raw.results.size(); ++k) {
      const ClassResult &r = raw.results[k], &s = sig.results[k];
      EXPECT_TRUE(std::isnan(r.brier.over_labels));
      EXPECT_TRUE(std::isnan(r.brier.over_detections));
      EXPECT_TRUE(std::isnan(r.brier.over_all));
      EXPECT_TRUE(std::isnan(r.calibration.ece));
      EXPECT_EQ(r.brier.num_label_terms, 2);  // the support is still there
      // AP, the curve and the operating point do not depend on the transform (bit for bit).
      EXPECT_EQ(r.ap_r40, s.ap_r40);
      EXPECT_EQ(r.ap_r11, s.ap_r11);
      ASSERT_EQ(r.curve.size(), s.curve.size());
      for (size_t i = 0; i < r.curve.size(); ++i)
        EXPECT_EQ(r.curve[i].threshold, s.curve[i].threshold);
      EXPECT_EQ(r.at_threshold.tp, s.at_threshold.tp);
      // Sigmoid: the TPs 2.0 and 40.0 (sigmoid(40) = 1 - 4e-18, rounds to 1), the FP -1.0.
      const double p2 = 1.0 / (1.0 + std::exp(-2.0)), pm1 = 1.0 / (1.0 + std::exp(1.0));
      EXPECT_NEAR(s.brier.over_labels, ((1 - p2) * (1 - p2) + 0.0) / 2, 1e-12);
      EXPECT_NEAR(s.brier.over_detections, ((1 - p2) * (1 - p2) + pm1 * pm1) / 3, 1e-12);
      EXPECT_FALSE(std::isnan(s.calibration.ece));
    }
  }
  EXPECT_EQ(ApplyScoreTransform(ScoreTransform::kSigmoid, 0.0), 0.5);
  EXPECT_EQ(ApplyScoreTransform(ScoreTransform::kSigmoid, -1000.0), 0.0);
  EXPECT_EQ(ParseScoreTransform("SIGMOID"), ScoreTransform::kSigmoid);
  EXPECT_FALSE(ParseScoreTransform("softmax").has_value());
}

}  // namespace
}  // namespace stereodet
