#include "stereodet/eval/filter.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

using testing_objects::Car2D;
using testing_objects::CarModerate2D;

// The paper's instability of naive filtering: a label just under a min-area bound whose matched
// detection is just above it. Naive: the label is struck, the detection becomes a FP. Stable: the
// pair is dropped as a whole (neither TP nor FP).
TEST(FilterTest, NaiveFilterTurnsAMatchedDetectionIntoAFalsePositive) {
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
    const EvalResult result = Evaluate({f}, options);  // keeps the result alive
    const ClassResult& r = result.results.at(0);
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

// Curves under a filter, by hand: a passing pair (score 0.8) and a label of 9900 px^2 matched by a
// detection of 10100 px^2 (score 0.9) under min-area=10000. Naive: the 0.9 detection is a FP, so
// precision is 0 then 1/2 at recall 1: AP_R40 50. Stable: the failing pair drops out: AP_R40 100.
TEST(FilterTest, CurvesOfExactMatchersByHand) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 99, 100, 0), Car2D(300, 0, 500, 100, 0)};
  f.detections = {Car2D(0, 0, 101, 100, 0, 0.9), Car2D(300, 0, 500, 100, 0, 0.8)};
  for (Matcher m : {Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options = CarModerate2D(m);
    options.filter.conditions = ParseFilterConditions("min-area=10000");
    const EvalResult result = Evaluate({f}, options);
    const ClassResult& r = result.results.at(0);
    ASSERT_TRUE(r.filtered.has_value());
    const FilteredStats& fs = *r.filtered;
    ASSERT_EQ(fs.naive_curve.curve.size(), 2u) << MatcherName(m);
    EXPECT_EQ(fs.naive_curve.curve[0].fp, 1);
    EXPECT_EQ(fs.naive_curve.curve[1].tp, 1);
    EXPECT_NEAR(fs.naive_curve.ap_r40, 50.0, 1e-9) << MatcherName(m);
    EXPECT_NEAR(fs.stable_curve.ap_r40, 100.0, 1e-9) << MatcherName(m);
    EXPECT_NEAR(fs.stable_curve.aos_r40, 100.0, 1e-9) << MatcherName(m);
    ASSERT_EQ(fs.stable_curve.curve.size(), 1u);  // nothing counts at 0.9
    EXPECT_EQ(fs.stable_curve.curve[0].tp, 1);
    EXPECT_EQ(fs.stable_curve.curve[0].fp, 0);
    EXPECT_EQ(fs.stable_curve.curve[0].fn, 0);
    EXPECT_NEAR(r.ap_r40, 100.0, 1e-9);  // unfiltered: both pairs
  }
  // KITTI matcher, stable: the unfiltered thresholds (0.9 and 0.8); at 0.9 nothing counts (0 / 0),
  // at 0.8 the passing pair.
  EvalOptions options = CarModerate2D(Matcher::kKitti);
  options.filter.conditions = ParseFilterConditions("min-area=10000");
  const EvalResult result = Evaluate({f}, options);
  const FilteredStats& fs = *result.results.at(0).filtered;
  ASSERT_EQ(fs.stable_curve.curve.size(), 2u);
  EXPECT_EQ(fs.stable_curve.curve[0].tp + fs.stable_curve.curve[0].fp, 0);
  EXPECT_EQ(fs.stable_curve.curve[1].tp, 1);
  EXPECT_EQ(fs.stable_curve.curve[1].fp, 0);
  ASSERT_EQ(fs.naive_curve.curve.size(), 1u);  // one label left, one threshold (0.8)
  EXPECT_EQ(fs.naive_curve.curve[0].tp, 1);
  EXPECT_EQ(fs.naive_curve.curve[0].fp, 1);
}

// The mirror case: the label passes (10100 px^2) and its detection fails (9900 px^2). Naive: the
// label is missed (FN); stable: the pair drops out, nothing counts. Every matcher, curve and
// operating point.
TEST(FilterTest, PassingLabelWithFailingDetectionDropsOutWhenStable) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 101, 100, 0), Car2D(300, 0, 500, 100, 0)};
  f.detections = {Car2D(0, 0, 99, 100, 0, 0.9), Car2D(300, 0, 500, 100, 0, 0.8)};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options = CarModerate2D(m);
    options.filter.conditions = ParseFilterConditions("min-area=10000");
    const EvalResult result = Evaluate({f}, options);
    const FilteredStats& fs = *result.results.at(0).filtered;
    EXPECT_EQ(fs.stable.tp, 1) << MatcherName(m);
    EXPECT_EQ(fs.stable.fn, 0) << MatcherName(m);
    EXPECT_EQ(fs.naive.fn, 1) << MatcherName(m);
    ASSERT_FALSE(fs.stable_curve.curve.empty());
    EXPECT_EQ(fs.stable_curve.curve.back().tp, 1) << MatcherName(m);
    EXPECT_EQ(fs.stable_curve.curve.back().fn, 0) << MatcherName(m);
    EXPECT_EQ(fs.naive_curve.curve.back().fn, 1) << MatcherName(m);
    if (m != Matcher::kKitti) {
      EXPECT_NEAR(fs.stable_curve.ap_r40, 100.0, 1e-9) << MatcherName(m);
      EXPECT_NEAR(fs.naive_curve.ap_r40, 50.0, 1e-9)
          << MatcherName(m);  // recall 1/2 at precision 1
    }
  }
}

// Properties on random frames, every matcher: a filter everything passes leaves the curves and AP
// unchanged in both modes; and under a real filter, each mode's curve at the operating threshold
// has the counts of that mode's operating point.
TEST(FilterTest, CurvesAgreeWithUnfilteredAndWithTheOperatingPoint) {
  RandomFramesOptions ro;
  ro.num_frames = 30;
  ro.crowded = true;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options;
    options.matcher = m;
    options.metrics = {OverlapKind::k2D, OverlapKind::kBev};
    options.filter.conditions = ParseFilterConditions("min-area=0");
    const EvalResult all_pass = Evaluate(frames, options);
    for (const ClassResult& r : all_pass.results) {
      if (!r.evaluated) continue;
      for (const FilteredCurve* c : {&r.filtered->naive_curve, &r.filtered->stable_curve}) {
        EXPECT_NEAR(c->ap_r40, r.ap_r40, 1e-9) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_NEAR(c->ap_r11, r.ap_r11, 1e-9) << MatcherName(m) << ' ' << r.class_name;
        ASSERT_EQ(c->curve.size(), r.curve.size()) << MatcherName(m) << ' ' << r.class_name;
        for (size_t k = 0; k < r.curve.size(); ++k) {
          EXPECT_EQ(c->curve[k].tp, r.curve[k].tp);
          EXPECT_EQ(c->curve[k].fp, r.curve[k].fp);
          EXPECT_EQ(c->curve[k].fn, r.curve[k].fn);
        }
      }
    }
    if (m == Matcher::kKitti) continue;  // its curve has only the devkit's thresholds
    options.filter.conditions = ParseFilterConditions("min-area=3000,max-distance=40");
    options.score_threshold = 0.5;
    const EvalResult filtered = Evaluate(frames, options);
    int nontrivial = 0;
    for (const ClassResult& r : filtered.results) {
      if (!r.evaluated) continue;
      auto at = [&](const FilteredCurve& c, const OperatingPoint& op) {
        CurvePoint p;
        p.fn = op.tp + op.fn;  // nothing detected above every threshold: all counted labels are FN
        for (const CurvePoint& q : c.curve) {
          if (q.threshold >= 0.5) p = q;
        }
        EXPECT_EQ(p.tp, op.tp) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_EQ(p.fp, op.fp) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_EQ(p.fn, op.fn) << MatcherName(m) << ' ' << r.class_name;
      };
      at(r.filtered->naive_curve, r.filtered->naive);
      at(r.filtered->stable_curve, r.filtered->stable);
      nontrivial += r.filtered->stable.tp > 0 ? 1 : 0;
    }
    EXPECT_GT(nontrivial, 0);
  }
}

// The stable filter's property (docs/metrics.md, "Filters"): its counts are the unfiltered
// association recounted under the filter - a matched pair is a TP when label and detection both
// pass and drops out otherwise, an unmatched detection (label) is a FP (FN) when it passes. So it
// never creates an error: every FP and FN it counts is one of the unfiltered evaluation, and
// moving an object across the filter's bound changes only that object's own term. Checked against
// the per-row records of the unfiltered association on random frames, for every matcher; the naive
// filter, the control, does create errors there (a pair whose label fails leaves its detection a
// FP).
TEST(FilterTest, StableFilterRecountsTheUnfilteredAssociationOnRandomFrames) {
  const std::vector<FilterCondition> conditions =
      ParseFilterConditions("min-height=45,max-distance=30");
  int naive_created_errors = 0, cells = 0;
  for (const uint64_t seed : {11u, 12u, 13u}) {
    RandomFramesOptions ro;
    ro.num_frames = 40;
    ro.crowded = seed != 13;
    ro.position_noise = 0.08;  // boxes that straddle the filter's bound, label or detection first
    ro.seed = seed;
    const std::vector<EvalFrame> frames = RandomFrames(ro);
    for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
      EvalOptions options;
      options.matcher = m;
      options.metrics = {OverlapKind::k2D, OverlapKind::kBev};
      options.filter.conditions = conditions;
      options.score_threshold = 0.3;
      options.keep_records = true;
      options.num_threads = 1;
      const EvalResult result = Evaluate(frames, options);
      for (const ClassResult& r : result.results) {
        if (!r.evaluated) continue;
        SCOPED_TRACE(std::string(MatcherName(m)) + " seed " + std::to_string(seed) + " " +
                     r.class_name + " " + OverlapKindName(r.metric) + " " +
                     DifficultyName(r.difficulty));
        int64_t tp = 0, fp = 0, fn = 0, all_tp = 0, all_fp = 0, all_fn = 0;
        for (const MatchRecord& row : r.records) {
          const EvalFrame& frame = frames.at(row.frame);
          const bool label_passes =
              row.label >= 0 && PassesFilter(frame.labels.at(row.label), true, conditions);
          const bool det_passes =
              row.detection >= 0 &&
              PassesFilter(frame.detections.at(row.detection), false, conditions);
          switch (row.outcome) {
            case Outcome::kTp:
              ++all_tp;
              tp += label_passes && det_passes ? 1 : 0;
              break;
            case Outcome::kFp:
              ++all_fp;
              fp += det_passes ? 1 : 0;
              break;
            case Outcome::kFn:
              ++all_fn;
              fn += label_passes ? 1 : 0;
              break;
            default:
              break;
          }
        }
        ASSERT_TRUE(r.filtered.has_value());
        const OperatingPoint& stable = r.filtered->stable;
        EXPECT_EQ(stable.tp, tp);
        EXPECT_EQ(stable.fp, fp);
        EXPECT_EQ(stable.fn, fn);
        // Hence no error created: at most the unfiltered evaluation's.
        EXPECT_LE(stable.fp, all_fp);
        EXPECT_LE(stable.fn, all_fn);
        EXPECT_LE(stable.tp, all_tp);
        // The records are the unfiltered operating point's.
        EXPECT_EQ(all_tp, r.at_threshold.tp);
        EXPECT_EQ(all_fp, r.at_threshold.fp);
        EXPECT_EQ(all_fn, r.at_threshold.fn);
        ++cells;
        naive_created_errors += r.filtered->naive.fp > fp || r.filtered->naive.fn > fn ? 1 : 0;
      }
    }
  }
  EXPECT_GT(cells, 20);
  EXPECT_GT(naive_created_errors, 0);  // the control: the property is not true of any filter
}

TEST(FilterTest, ParsesAndRejects) {
  const auto c = ParseFilterConditions("min-height=25, max-distance=40,difficulty=moderate");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[2].bound, FilterBound::kDifficulty);
  EXPECT_EQ(c[2].value, 1);
  EXPECT_THROW(ParseFilterConditions("min-size=3"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area=abc"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area"), std::invalid_argument);
}

TEST(FilterTest, ASweepOfMoreThan100000ValuesIsAnErrorNotAnOverflow) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 99, 100, 0)};
  EvalOptions options = CarModerate2D(Matcher::kKitti);
  EXPECT_EQ(FilterSweep({f}, options, FilterBound::kMinArea, 0, 100, 0.002).size(), 50001u);
  for (double step : {0.0009, 1e-9, 1e-300}) {  // 111112 values, 1e11, 1e302
    try {
      FilterSweep({f}, options, FilterBound::kMinArea, 0, 100, step);
      ADD_FAILURE() << "no error for step " << step;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("sweep has too many values"), std::string::npos);
    }
  }
}

TEST(FilterTest, FilterModeRoundTrip) {
  for (FilterMode m : {FilterMode::kNaive, FilterMode::kStable}) {
    EXPECT_EQ(ParseFilterMode(FilterModeName(m)), m) << FilterModeName(m);
  }
  EXPECT_EQ(ParseFilterMode("strict"), std::nullopt);
}

TEST(FilterTest, FilterBoundRoundTrip) {
  const FilterBound all[] = {
      FilterBound::kMinHeight,     FilterBound::kMaxHeight,   FilterBound::kMinWidth,
      FilterBound::kMaxWidth,      FilterBound::kMinArea,     FilterBound::kMaxArea,
      FilterBound::kMinDistance,   FilterBound::kMaxDistance, FilterBound::kMaxOcclusion,
      FilterBound::kMaxTruncation, FilterBound::kDifficulty,
  };
  for (FilterBound b : all) {
    EXPECT_EQ(ParseFilterBound(FilterBoundName(b)), b) << FilterBoundName(b);
    EXPECT_STRNE(FilterBoundName(b), "?");
  }
  EXPECT_STREQ(FilterBoundName(FilterBound::kMaxTruncation), "max-truncation");
  EXPECT_EQ(ParseFilterBound("min-depth"), std::nullopt);
}

// difficulty= takes KITTI's level names (any case, as --difficulties) or their index.
TEST(FilterTest, DifficultyConditionByNameOrIndex) {
  const std::vector<FilterCondition> c =
      ParseFilterConditions("difficulty=easy, difficulty=Moderate,difficulty=2");
  ASSERT_EQ(c.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(c[i].bound, FilterBound::kDifficulty);
    EXPECT_EQ(c[i].value, i);
  }
  EXPECT_THROW(ParseFilterConditions("difficulty=medium"), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
