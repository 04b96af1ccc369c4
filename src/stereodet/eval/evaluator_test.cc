#include "stereodet/eval/evaluator.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "stereodet/eval/optimal_matcher.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/kitti/label_io.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

std::vector<EvalFrame> ReadFixture(const fs::path& dir) {
  std::vector<EvalFrame> frames;
  std::vector<fs::path> labels;
  for (const auto& e : fs::directory_iterator(dir / "label_2")) labels.push_back(e.path());
  std::sort(labels.begin(), labels.end());
  for (const fs::path& p : labels) {
    EvalFrame f;
    f.id = p.stem().string();
    f.labels = ReadObjects(p, {ObjectFileKind::kLabel, false}).objects;
    f.detections = ReadObjects(dir / "det" / p.filename(), {ObjectFileKind::kDetection, false}).objects;
    frames.push_back(std::move(f));
  }
  return frames;
}

// The numbers KITTI's evaluation code printed on tests/data/eval_small (see its README.md).
TEST(Evaluator, AgreesWithTheDevkitOnTheFixture) {
  const fs::path dir = fs::path(STEREODET_SOURCE_DIR) / "tests/data/eval_small";
  const std::vector<EvalFrame> frames = ReadFixture(dir);
  ASSERT_EQ(frames.size(), 12u);
  EvalOptions options;
  options.num_threads = 2;
  const EvalResult result = Evaluate(frames, options);
  std::ifstream expected(dir / "devkit_expected.txt");
  std::string line;
  int checked = 0;
  while (std::getline(expected, line)) {
    std::istringstream in(line);
    std::string name, which;
    double v[3];
    in >> name >> which >> v[0] >> v[1] >> v[2];
    const bool aos = name.find("orientation") != std::string::npos;
    const OverlapKind kind = name.find("_ground") != std::string::npos ? OverlapKind::kBev
                             : name.find("_3d") != std::string::npos   ? OverlapKind::k3D
                                                                       : OverlapKind::k2D;
    const std::string cls = name.substr(0, name.find('_'));
    for (int d = 0; d < 3; ++d) {
      const ClassResult* r = result.Find(cls, kind, static_cast<Difficulty>(d));
      ASSERT_NE(r, nullptr) << line;
      const double ours = which == "AP:" ? (aos ? r->aos_r11 : r->ap_r11) : (aos ? r->aos_r40 : r->ap_r40);
      EXPECT_NEAR(ours, v[d], 1e-4) << line << " difficulty " << d;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 72);
}

TEST(Evaluator, ClassWithoutDetectionsIsNotEvaluatedLikeTheDevkit) {
  RandomFramesOptions ro;
  ro.num_frames = 20;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  for (EvalFrame& f : frames) {
    std::erase_if(f.detections, [](const Object& d) { return d.type == "Cyclist"; });
  }
  EvalOptions options;
  const EvalResult r = Evaluate(frames, options);
  EXPECT_FALSE(r.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  EXPECT_TRUE(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  options.require_detections = false;
  const EvalResult all = Evaluate(frames, options);
  EXPECT_TRUE(all.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  EXPECT_EQ(all.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->ap_r40, 0.0);
}

TEST(Evaluator, AlphaMinus10AnywhereDisablesAos) {
  RandomFramesOptions ro;
  ro.num_frames = 10;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  EXPECT_TRUE(Evaluate(frames, options).aos_computed);
  frames[3].detections.at(0).alpha = -10;
  const EvalResult r = Evaluate(frames, options);
  EXPECT_FALSE(r.aos_computed);
  EXPECT_TRUE(std::isnan(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->aos_r40));
}

// The three matchers agree on TP counts at each threshold up to greedy's mistakes, and the optimal
// curve's counts at the operating threshold equal its association's.
TEST(Evaluator, OptimalCurveMatchesItsAssociationAndBeatsGreedy) {
  RandomFramesOptions ro;
  ro.num_frames = 60;
  ro.crowded = true;
  ro.labels_per_frame = 9;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.score_threshold = 0.5;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::kBev};
  const EvalResult kitti = Evaluate(frames, options);
  options.matcher = Matcher::kOptimal;
  const EvalResult optimal = Evaluate(frames, options);
  options.matcher = Matcher::kVoc;
  const EvalResult voc = Evaluate(frames, options);
  for (Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
    const ClassResult& o = *optimal.Find("Car", OverlapKind::kBev, d);
    CurvePoint at;
    for (const CurvePoint& p : o.curve) {
      if (p.threshold >= 0.5) at = p;
    }
    EXPECT_EQ(at.tp, o.at_threshold.tp);
    EXPECT_EQ(at.fp, o.at_threshold.fp);
    EXPECT_EQ(at.fn, o.at_threshold.fn);
    EXPECT_GE(o.at_threshold.tp, kitti.Find("Car", OverlapKind::kBev, d)->at_threshold.tp);
    EXPECT_GE(o.at_threshold.tp, voc.Find("Car", OverlapKind::kBev, d)->at_threshold.tp);
    EXPECT_GT(o.ap_r40, 0.0);
    EXPECT_FALSE(std::isnan(o.ap_voc));
  }
}

TEST(Curves, InterpolatedApOfAPerfectCurveIs100) {
  // 40 labels, found one by one with precision 1: R40 = 100 (no devkit slot quirk here).
  std::vector<CurveEvent> events;
  for (int i = 0; i < 40; ++i) events.push_back(CurveEvent{1.0 - i / 100.0, 1, 0, -1});
  const std::vector<CurvePoint> curve = BuildCurve(events, 40);
  EXPECT_DOUBLE_EQ(InterpolatedApR40(curve), 100.0);
  EXPECT_DOUBLE_EQ(InterpolatedApR11(curve), 100.0);
  EXPECT_DOUBLE_EQ(EveryPointAp(curve), 100.0);
  EXPECT_DOUBLE_EQ(BestF1(curve).f1, 1.0);
}

TEST(Curves, EveryPointApIntegratesTheEnvelope) {
  // Labels: 2. Scores: TP, FP, TP -> (P, R) = (1, .5), (.5, .5), (2/3, 1).
  const std::vector<CurvePoint> curve =
      BuildCurve({{0.9, 1, 0, -1}, {0.8, 0, 1, 0}, {0.7, 1, 0, -1}}, 2);
  ASSERT_EQ(curve.size(), 3u);
  EXPECT_NEAR(EveryPointAp(curve), (0.5 * 1.0 + 0.5 * 2.0 / 3.0) * 100, 1e-12);
  // R11: r = 0..0.5 -> 1 (6 levels), r = 0.6..1 -> 2/3 (5 levels).
  EXPECT_NEAR(InterpolatedApR11(curve), (6 * 1.0 + 5 * 2.0 / 3.0) / 11 * 100, 1e-12);
}

// Brier three ways, by hand: one TP (s = 0.9), one FP (s = 0.4), one FN.
TEST(ScoreMetrics, BrierThreeWaysByHand) {
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
    const ClassResult& r = Evaluate({f}, options).results.at(0);
    EXPECT_NEAR(r.brier.over_labels, (0.01 + 1.0) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_detections, (0.01 + 0.16) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_all, (0.01 + 0.16 + 1.0) / 3, 1e-12);
    // Reliability, 10 bins: 0.4 (FP) in bin 4, 0.9 (TP) in bin 9. ECE = (0.4 + 0.1) / 2.
    EXPECT_EQ(r.calibration.bins[4].count, 1);
    EXPECT_EQ(r.calibration.bins[9].tp_fraction, 1.0);
    EXPECT_NEAR(r.calibration.ece, 0.25, 1e-12);
  }
}

// The paper's instability of naive filtering: a label just under a min-area bound whose matched
// detection is just above it. Naive: the label is struck, the detection becomes a FP. Stable: the
// pair is dropped as a whole (neither TP nor FP).
TEST(Filters, NaiveFilterTurnsAMatchedDetectionIntoAFalsePositive) {
  EvalFrame f;
  Object label, det;
  label.type = det.type = "Car";
  label.box = {0, 0, 99, 100};  // area 9900
  det.box = {0, 0, 101, 100};   // area 10100, IoU 0.98
  det.score = 0.9;
  f.labels = {label};
  f.detections = {det};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  options.filter.conditions = ParseFilterConditions("min-area=10000");
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const ClassResult& r = Evaluate({f}, options).results.at(0);
    ASSERT_TRUE(r.filtered.has_value());
    EXPECT_EQ(r.filtered->naive.fp, 1) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.fp, 0) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.tp, 0) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.fn, 0) << MatcherName(m);
  }
  options.filter.conditions.clear();  // the sweep adds its own bound
  const std::vector<SweepRow> rows =
      FilterSweep({f}, options, FilterBound::kMinArea, 9000, 11000, 1000);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].stats.stable.tp, 1);  // 9000: both pass
  EXPECT_EQ(rows[1].stats.naive.fp, 1);   // 10000: the naive FP
  EXPECT_EQ(rows[2].stats.naive.fp, 0);   // 11000: both struck
}

TEST(Filters, ParsesAndRejects) {
  const auto c = ParseFilterConditions("min-height=25, max-distance=40,difficulty=moderate");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[2].bound, FilterBound::kDifficulty);
  EXPECT_EQ(c[2].value, 1);
  EXPECT_THROW(ParseFilterConditions("min-size=3"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area=abc"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area"), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
