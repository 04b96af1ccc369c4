#include "stereodet/eval/bootstrap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

// Bit for bit, NaN equal to NaN.
bool Same(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::memcmp(&a, &b, sizeof a) == 0;
}

// The resampled frame list, materialised: frame f repeated counts[f] times, in frame order.
std::vector<EvalFrame> Materialise(const std::vector<EvalFrame>& frames,
                                   const std::vector<int32_t>& counts) {
  std::vector<EvalFrame> out;
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int32_t k = 0; k < counts[f]; ++k) out.push_back(frames[f]);
  }
  return out;
}

// The metric as Evaluate reports it for a cell (NaN where the cell is not evaluated).
double Reported(const ClassResult& r, BootstrapMetric m) {
  if (!r.evaluated) return std::nan("");
  switch (m) {
    case BootstrapMetric::kApR40:
      return r.ap_r40;
    case BootstrapMetric::kApR11:
      return r.ap_r11;
    case BootstrapMetric::kApVoc:
      return r.ap_voc;
    case BootstrapMetric::kBrierLabels:
      return r.brier.over_labels;
    case BootstrapMetric::kBrierDetections:
      return r.brier.over_detections;
    case BootstrapMetric::kBrierAll:
      return r.brier.over_all;
  }
  return 0;
}

// The metric as Evaluate reports it for a breakdown bin.
double Reported(const BreakdownBin& b, BootstrapMetric m) {
  switch (m) {
    case BootstrapMetric::kApR40:
      return b.curve.ap_r40;
    case BootstrapMetric::kApR11:
      return b.curve.ap_r11;
    case BootstrapMetric::kApVoc:
      return b.curve.ap_voc;
    case BootstrapMetric::kBrierLabels:
      return b.brier.over_labels;
    case BootstrapMetric::kBrierDetections:
      return b.brier.over_detections;
    case BootstrapMetric::kBrierAll:
      return b.brier.over_all;
  }
  return 0;
}

std::vector<EvalFrame> SmallFrames(uint64_t seed, int num_frames = 24) {
  RandomFramesOptions o;
  o.num_frames = num_frames;
  o.score_decimals = 2;  // ties between frames, as KITTI files have them
  o.seed = seed;
  return RandomFrames(o);
}

// Every resample's values against Evaluate on the materialised frame list: bit-identical AP and
// Brier, in every cell, and the estimates against Evaluate on the frames as given.
void ExpectExact(const std::vector<EvalFrame>& frames, const EvalOptions& eval, int resamples) {
  BootstrapOptions b;
  b.num_resamples = resamples;
  b.seed = 7;
  b.keep_samples = true;
  b.num_threads = 2;
  const BootstrapResult boot = Bootstrap(frames, eval, b);
  const EvalResult whole = Evaluate(frames, eval);
  ASSERT_EQ(boot.cells.size(), whole.results.size());
  int compared = 0;
  for (size_t c = 0; c < boot.cells.size(); ++c) {
    for (const BootstrapMetric m : BootstrapMetrics(eval.matcher)) {
      EXPECT_TRUE(Same(boot.cells[c].Get(m).estimate, Reported(whole.results[c], m)))
          << "estimate, cell " << c << " " << BootstrapMetricName(m) << ": "
          << boot.cells[c].Get(m).estimate << " vs " << Reported(whole.results[c], m);
    }
  }
  for (int r = 0; r < resamples; ++r) {
    const std::vector<int32_t> counts =
        BootstrapFrameCounts(static_cast<int64_t>(frames.size()), b.seed, r);
    const EvalResult brute = Evaluate(Materialise(frames, counts), eval);
    ASSERT_EQ(brute.results.size(), boot.cells.size());
    for (size_t c = 0; c < boot.cells.size(); ++c) {
      const ClassResult& expected = brute.results[c];
      for (const BootstrapMetric m : BootstrapMetrics(eval.matcher)) {
        const double got = boot.cells[c].Get(m).samples[r];
        EXPECT_TRUE(Same(got, Reported(expected, m)))
            << "resample " << r << ", " << expected.class_name << " "
            << OverlapKindName(expected.metric) << " " << DifficultyName(expected.difficulty) << " "
            << BootstrapMetricName(m) << ": " << got << " vs " << Reported(expected, m);
        compared += std::isnan(got) ? 0 : 1;
      }
    }
  }
  EXPECT_GT(compared, resamples * 10);  // most cells have numbers
}

// What ExpectBinsExact compared: numbers, and NaN where Evaluate has NaN AP for lack of labels.
struct BinComparison {
  int numbers = 0;
  int nan_ap_with_brier = 0;  // AP NaN (no valid label in the bin), Brier over detections defined
};

// ExpectExact for the breakdown bins: every bin of every cell, in every resample, against the bins
// of Evaluate on the materialised frame list, bit for bit; the estimates against Evaluate's bins.
BinComparison ExpectBinsExact(const std::vector<EvalFrame>& frames, const EvalOptions& eval,
                              int resamples) {
  BootstrapOptions b;
  b.num_resamples = resamples;
  b.seed = 11;
  b.keep_samples = true;
  b.num_threads = 2;
  const BootstrapResult boot = Bootstrap(frames, eval, b);
  const EvalResult whole = Evaluate(frames, eval);
  BinComparison seen;
  EXPECT_EQ(boot.cells.size(), whole.results.size());
  if (boot.cells.size() != whole.results.size()) return seen;
  // A bin's values against Evaluate's (`r`: the resample, -1 for the estimate).
  auto compare = [&](const EvalResult& expected_result, int r) {
    for (size_t c = 0; c < boot.cells.size(); ++c) {
      const BootstrapCell& cell = boot.cells[c];
      const ClassResult& expected = expected_result.results[c];
      if (!cell.evaluated) {
        EXPECT_TRUE(cell.breakdown.empty());
        continue;
      }
      const size_t num_bins = whole.results[c].breakdown.size();
      EXPECT_EQ(cell.breakdown.size(), num_bins);
      if (cell.breakdown.size() != num_bins) continue;
      for (size_t k = 0; k < num_bins; ++k) {
        const BootstrapBin& bin = cell.breakdown[k];
        EXPECT_EQ(bin.axis, whole.results[c].breakdown[k].axis);
        EXPECT_EQ(bin.lower, whole.results[c].breakdown[k].lower);
        EXPECT_EQ(bin.upper, whole.results[c].breakdown[k].upper);
        // A resample where the cell is not evaluated has no bins: every value NaN.
        const bool has_bins = expected.evaluated;
        if (has_bins) {
          EXPECT_EQ(expected.breakdown.size(), num_bins);
          if (expected.breakdown.size() != num_bins) continue;
        }
        for (const BootstrapMetric m : BootstrapMetrics(eval.matcher)) {
          const double got = r < 0 ? bin.Get(m).estimate : bin.Get(m).samples[r];
          const double want = has_bins ? Reported(expected.breakdown[k], m) : std::nan("");
          EXPECT_TRUE(Same(got, want))
              << (r < 0 ? std::string("estimate") : "resample " + std::to_string(r)) << ", "
              << expected.class_name << " " << OverlapKindName(expected.metric) << " "
              << DifficultyName(expected.difficulty) << " " << BreakdownAxisName(bin.axis) << " "
              << BreakdownBinName(bin.lower, bin.upper) << " " << BootstrapMetricName(m) << ": "
              << got << " vs " << want;
          seen.numbers += std::isnan(got) ? 0 : 1;
        }
        if (r >= 0 && has_bins && std::isnan(bin.Get(BootstrapMetric::kApR40).samples[r]) &&
            !std::isnan(bin.Get(BootstrapMetric::kBrierDetections).samples[r])) {
          ++seen.nan_ap_with_brier;
        }
      }
    }
  };
  compare(whole, -1);
  for (int r = 0; r < resamples; ++r) {
    const std::vector<int32_t> counts =
        BootstrapFrameCounts(static_cast<int64_t>(frames.size()), b.seed, r);
    const EvalResult brute = Evaluate(Materialise(frames, counts), eval);
    EXPECT_EQ(brute.results.size(), boot.cells.size());
    if (brute.results.size() != boot.cells.size()) return seen;
    compare(brute, r);
  }
  return seen;
}

// Random frames where every third detection is a 2D detector's (no 3D box, so no distance: it
// counts in every distance bin), with the axes of every kind: distance with a bin that holds no
// label ([-inf, 0): every label is in front of the camera) but the unplaced detections, height,
// occlusion (labels only: every detection in every bin) and image columns.
struct BinCase {
  std::vector<EvalFrame> frames;
  EvalOptions eval;
};
BinCase BreakdownCase(uint64_t seed, Matcher matcher, int num_frames = 20) {
  RandomFramesOptions o;
  o.num_frames = num_frames;
  o.score_decimals = 2;
  o.seed = seed;
  BinCase c;
  c.frames = RandomFrames(o);
  int k = 0;
  for (EvalFrame& f : c.frames) {
    for (Object& d : f.detections) {
      if (k++ % 3 == 0) d.SetNot3DEstimated();
    }
  }
  c.eval.matcher = matcher;
  c.eval.num_threads = 2;
  c.eval.breakdowns = {ParseBreakdown("distance=-inf,0,20,40,inf"),
                       ParseBreakdown("height=0,40,inf"), ParseBreakdown("occlusion=0,1,3"),
                       ParseBreakdown("column=-inf,400,800,inf")};
  return c;
}

void ExpectBinsExactAndSeen(const BinCase& c, int resamples) {
  const BinComparison seen = ExpectBinsExact(c.frames, c.eval, resamples);
  EXPECT_GT(seen.numbers, resamples * 50);  // most bins have numbers
  // The label-free bin: NaN AP but a Brier over its (unplaced) detections, in every resample where
  // its cell has any.
  EXPECT_GT(seen.nan_ap_with_brier, resamples);
}

TEST(BootstrapTest, BreakdownBinsMatchEvaluateOnEveryResampleKitti) {
  BinCase c = BreakdownCase(21, Matcher::kKitti);
  c.eval.metrics = {OverlapKind::k2D, OverlapKind::k3D, OverlapKind::kLet3D};
  ExpectBinsExactAndSeen(c, 10);
}

TEST(BootstrapTest, BreakdownBinsMatchEvaluateOnEveryResampleOptimal) {
  BinCase c = BreakdownCase(22, Matcher::kOptimal);
  c.eval.metrics = {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::kLetBev};
  ExpectBinsExactAndSeen(c, 10);
}

TEST(BootstrapTest, BreakdownBinsMatchEvaluateOnEveryResampleVocAndOperatingPoint) {
  BinCase c = BreakdownCase(23, Matcher::kVoc);
  c.eval.score_threshold = 0.3;
  c.eval.metrics = {OverlapKind::k2D, OverlapKind::k3D};
  ExpectBinsExactAndSeen(c, 10);
}

TEST(BootstrapTest, BreakdownBinsMatchEvaluateOnEveryResampleOpenPcdet) {
  BinCase c = BreakdownCase(24, Matcher::kKitti, 16);
  c.eval.compat = EvalCompat::kOpenPcdet;
  c.eval.score_threshold = 0.4;
  c.eval.metrics = {OverlapKind::k2D, OverlapKind::kBev};
  ExpectBinsExactAndSeen(c, 6);
}

TEST(BootstrapTest, BreakdownBinsMatchEvaluateWithLogitScoresAndCrowdedScenes) {
  RandomFramesOptions o;
  o.num_frames = 14;
  o.crowded = true;
  o.seed = 25;
  BinCase c;
  c.frames = RandomFrames(o);
  for (EvalFrame& f : c.frames) {
    for (Object& d : f.detections) d.score = *d.score * 6 - 3;  // logits, outside [0, 1]
  }
  c.eval.num_threads = 2;
  c.eval.matcher = Matcher::kOptimal;
  c.eval.score_transform = ScoreTransform::kSigmoid;
  c.eval.breakdowns = {ParseBreakdown("distance=0,5,10,inf"), ParseBreakdown("height=0,60,inf")};
  EXPECT_GT(ExpectBinsExact(c.frames, c.eval, 5).numbers, 100);
  c.eval.matcher = Matcher::kKitti;
  EXPECT_GT(ExpectBinsExact(c.frames, c.eval, 5).numbers, 100);
}

// A bin (-inf, inf) is the whole cell: with the same draws its samples are the cell's, bit for bit
// (Brier; and AP for the exact matchers, whose bin curve is the cell's curve, except in a resample
// without a valid label, where the bin's AP is NaN and the cell's 0).
TEST(BootstrapTest, BreakdownBinOfEverythingHasTheCellsIntervals) {
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions eval;
    eval.matcher = matcher;
    eval.metrics = {OverlapKind::k2D};
    eval.num_threads = 2;
    eval.breakdowns = {ParseBreakdown("height=-inf,inf")};
    BootstrapOptions b;
    b.num_resamples = 40;
    b.keep_samples = true;
    const BootstrapResult boot = Bootstrap(SmallFrames(26), eval, b);
    for (const BootstrapCell& cell : boot.cells) {
      if (!cell.evaluated) continue;
      ASSERT_EQ(cell.breakdown.size(), 1u);
      std::vector<BootstrapMetric> same = {BootstrapMetric::kBrierLabels,
                                           BootstrapMetric::kBrierDetections,
                                           BootstrapMetric::kBrierAll};
      if (matcher != Matcher::kKitti) {
        same.insert(same.end(),
                    {BootstrapMetric::kApR40, BootstrapMetric::kApR11, BootstrapMetric::kApVoc});
      }
      for (const BootstrapMetric m : same) {
        for (int r = 0; r < b.num_resamples; ++r) {
          const double bin = cell.breakdown[0].Get(m).samples[r], whole = cell.Get(m).samples[r];
          // A resample without a valid label of the cell: the bin has no AP, the cell's curve 0.
          const bool ap = m == BootstrapMetric::kApR40 || m == BootstrapMetric::kApR11 ||
                          m == BootstrapMetric::kApVoc;
          const bool no_labels = ap && std::isnan(bin) && whole == 0.0;
          EXPECT_TRUE(Same(bin, whole) || no_labels)
              << MatcherName(matcher) << " " << BootstrapMetricName(m) << " resample " << r << ": "
              << bin << " vs " << whole;
        }
        if (cell.breakdown[0].Get(m).num_defined == cell.Get(m).num_defined) {
          EXPECT_TRUE(Same(cell.breakdown[0].Get(m).lower, cell.Get(m).lower));
          EXPECT_TRUE(Same(cell.breakdown[0].Get(m).upper, cell.Get(m).upper));
        }
      }
    }
  }
}

// Paired bins: every bin's A - B, resample by resample, is Bootstrap(A)'s bin minus Bootstrap(B)'s
// (the same frame counts), and A and B's own bins are Bootstrap's; A against A is exactly 0 in
// every defined bin. B drops a third of A's detections, halves the scores and leaves one class out
// of a frame set where that class is the only one: a cell evaluated in A alone has NaN bins.
TEST(BootstrapTest, PairedBinsAreTheDifferenceOfEachSetsBinsOnEveryResample) {
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal}) {
    const BinCase c = BreakdownCase(31, matcher, 16);
    const std::vector<EvalFrame>& a = c.frames;
    std::vector<EvalFrame> b = a;
    for (EvalFrame& f : b) {
      std::vector<Object> kept;
      for (size_t j = 0; j < f.detections.size(); ++j) {
        if (j % 3 == 2 || f.detections[j].type == "Cyclist") continue;
        kept.push_back(f.detections[j]);
        kept.back().score = *kept.back().score / 2;
      }
      f.detections = kept;
    }
    BootstrapOptions options;
    options.num_resamples = 25;
    options.keep_samples = true;
    const PairedBootstrapResult paired = PairedBootstrap(a, b, c.eval, options);
    const BootstrapResult alone_a = Bootstrap(a, c.eval, options);
    const BootstrapResult alone_b = Bootstrap(b, c.eval, options);
    int compared = 0, nan_cells = 0;
    for (size_t cell = 0; cell < paired.difference.cells.size(); ++cell) {
      const BootstrapCell& d = paired.difference.cells[cell];
      const BootstrapCell& x = alone_a.cells[cell];
      const BootstrapCell& y = alone_b.cells[cell];
      ASSERT_EQ(d.breakdown.size(), x.breakdown.size());
      ASSERT_EQ(paired.a.cells[cell].breakdown.size(), x.breakdown.size());
      ASSERT_EQ(paired.b.cells[cell].breakdown.size(), y.breakdown.size());
      if (y.breakdown.empty()) {
        nan_cells += !x.breakdown.empty();
        for (const BootstrapBin& bin : d.breakdown) {
          for (const BootstrapInterval& i : bin.intervals) EXPECT_TRUE(std::isnan(i.estimate));
        }
        continue;
      }
      ASSERT_EQ(x.breakdown.size(), y.breakdown.size());
      for (size_t k = 0; k < d.breakdown.size(); ++k) {
        for (int m = 0; m < kNumBootstrapMetrics; ++m) {
          const BootstrapInterval& di = d.breakdown[k].intervals[m];
          const BootstrapInterval& xi = x.breakdown[k].intervals[m];
          const BootstrapInterval& yi = y.breakdown[k].intervals[m];
          EXPECT_TRUE(Same(paired.a.cells[cell].breakdown[k].intervals[m].lower, xi.lower));
          EXPECT_TRUE(Same(paired.b.cells[cell].breakdown[k].intervals[m].upper, yi.upper));
          EXPECT_TRUE(Same(di.estimate, xi.estimate - yi.estimate));
          ASSERT_EQ(di.samples.size(), xi.samples.size());
          for (size_t r = 0; r < di.samples.size(); ++r) {
            EXPECT_TRUE(Same(di.samples[r], xi.samples[r] - yi.samples[r]))
                << "cell " << cell << " bin " << k << " metric " << m << " resample " << r;
            compared += !std::isnan(di.samples[r]);
          }
        }
      }
    }
    EXPECT_GT(compared, 500) << MatcherName(matcher);
    EXPECT_GT(nan_cells, 0) << MatcherName(matcher);  // Cyclist: evaluated in A alone
    const PairedBootstrapResult same = PairedBootstrap(a, a, c.eval, options);
    int zeros = 0;
    for (const BootstrapCell& cell : same.difference.cells) {
      for (const BootstrapBin& bin : cell.breakdown) {
        for (const BootstrapInterval& i : bin.intervals) {
          if (i.num_defined == 0) continue;
          EXPECT_EQ(i.estimate, 0.0);
          EXPECT_EQ(i.lower, 0.0);
          EXPECT_EQ(i.upper, 0.0);
          ++zeros;
        }
      }
    }
    EXPECT_GT(zeros, 50) << MatcherName(matcher);
  }
}

TEST(BootstrapTest, MatchesEvaluateOnEveryResampleKitti) {
  EvalOptions eval;
  eval.num_threads = 2;
  ExpectExact(SmallFrames(3), eval, 12);
}

TEST(BootstrapTest, MatchesEvaluateOnEveryResampleOptimal) {
  EvalOptions eval;
  eval.matcher = Matcher::kOptimal;
  eval.metrics = {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D, OverlapKind::kLetBev,
                  OverlapKind::kLet3D};
  eval.num_threads = 2;
  ExpectExact(SmallFrames(4), eval, 12);
}

TEST(BootstrapTest, MatchesEvaluateOnEveryResampleVocAndOperatingPoint) {
  EvalOptions eval;
  eval.matcher = Matcher::kVoc;
  eval.score_threshold = 0.3;
  eval.metrics = {OverlapKind::k2D, OverlapKind::k3D};
  eval.num_threads = 2;
  ExpectExact(SmallFrames(5), eval, 8);
}

TEST(BootstrapTest, MatchesEvaluateOnEveryResampleOpenPcdet) {
  EvalOptions eval;
  eval.compat = EvalCompat::kOpenPcdet;
  eval.score_threshold = 0.4;
  eval.metrics = {OverlapKind::k2D, OverlapKind::kBev};
  eval.num_threads = 2;
  ExpectExact(SmallFrames(6, 16), eval, 6);
}

TEST(BootstrapTest, MatchesEvaluateWithLogitScoresAndCrowdedScenes) {
  RandomFramesOptions o;
  o.num_frames = 16;
  o.crowded = true;
  o.seed = 9;
  std::vector<EvalFrame> frames = RandomFrames(o);
  for (EvalFrame& f : frames) {
    for (Object& d : f.detections) d.score = *d.score * 6 - 3;  // logits, outside [0, 1]
  }
  EvalOptions eval;
  eval.num_threads = 2;
  eval.score_transform = ScoreTransform::kSigmoid;
  ExpectExact(frames, eval, 6);
  // Without the transform the scores are not probabilities: Brier is NaN in every resample.
  eval.score_transform = ScoreTransform::kNone;
  BootstrapOptions b;
  b.num_resamples = 5;
  const BootstrapResult boot = Bootstrap(frames, eval, b);
  for (const BootstrapCell& c : boot.cells) {
    EXPECT_EQ(c.Get(BootstrapMetric::kBrierLabels).num_defined, 0);
    EXPECT_TRUE(std::isnan(c.Get(BootstrapMetric::kBrierLabels).lower));
  }
}

// Frames with one perfectly detected car and frames with one missed car: a resample with k hit
// frames of n has Brier over labels (n - k) / n (the TP's score is 1) and recall k / n.
TEST(BootstrapTest, HandComputedBrierInterval) {
  using testing_objects::Car;
  std::vector<EvalFrame> frames(4);
  for (int f = 0; f < 4; ++f) {
    frames[f].id = std::to_string(f);
    frames[f].labels = {Car({100, 100, 200, 200})};
    if (f < 2) frames[f].detections = {Car({100, 100, 200, 200}, 1.0)};
  }
  EvalOptions eval;
  eval.metrics = {OverlapKind::k2D};
  eval.difficulties = {Difficulty::kModerate};
  eval.classes = {KittiClassSpec("Car")};
  BootstrapOptions b;
  b.num_resamples = 200;
  b.keep_samples = true;
  const BootstrapResult boot = Bootstrap(frames, eval, b);
  ASSERT_EQ(boot.cells.size(), 1u);
  const BootstrapInterval& brier = boot.cells[0].Get(BootstrapMetric::kBrierLabels);
  EXPECT_DOUBLE_EQ(brier.estimate, 0.5);
  int with_hits = 0;
  for (int r = 0; r < b.num_resamples; ++r) {
    const std::vector<int32_t> w = BootstrapFrameCounts(4, b.seed, r);
    const int hits = w[0] + w[1];
    if (hits == 0) {
      // No detection at all: the devkit does not evaluate the class, nor does Evaluate.
      EXPECT_TRUE(std::isnan(brier.samples[r])) << r;
      EXPECT_TRUE(std::isnan(boot.cells[0].Get(BootstrapMetric::kApR40).samples[r])) << r;
    } else {
      EXPECT_DOUBLE_EQ(brier.samples[r], (4 - hits) / 4.0) << r;
      ++with_hits;
    }
  }
  EXPECT_EQ(brier.num_defined, with_hits);
  EXPECT_GT(with_hits, 180);  // (1/2)^4 of the resamples have no hit
  EXPECT_GE(brier.lower, 0.0);
  EXPECT_LT(brier.lower, 0.5);
  EXPECT_GT(brier.upper, 0.5);
  EXPECT_LE(brier.upper, 1.0);
}

TEST(BootstrapTest, OneFrameGivesADegenerateInterval) {
  std::vector<EvalFrame> frames = SmallFrames(11, 1);
  EvalOptions eval;
  eval.require_detections = false;
  BootstrapOptions b;
  b.num_resamples = 20;
  const BootstrapResult boot = Bootstrap(frames, eval, b);
  for (const BootstrapCell& c : boot.cells) {
    for (const BootstrapMetric m : BootstrapMetrics(eval.matcher)) {
      const BootstrapInterval& i = c.Get(m);
      if (std::isnan(i.estimate)) continue;
      EXPECT_EQ(i.lower, i.estimate);
      EXPECT_EQ(i.upper, i.estimate);
    }
  }
}

TEST(BootstrapTest, NoFramesGiveWhatEvaluateGives) {
  EvalOptions eval;
  eval.require_detections = false;
  BootstrapOptions b;
  b.num_resamples = 3;
  const BootstrapResult boot = Bootstrap({}, eval, b);
  const EvalResult whole = Evaluate({}, eval);
  ASSERT_EQ(boot.cells.size(), whole.results.size());
  for (size_t c = 0; c < boot.cells.size(); ++c) {
    EXPECT_TRUE(Same(boot.cells[c].Get(BootstrapMetric::kApR40).estimate, whole.results[c].ap_r40));
    EXPECT_TRUE(std::isnan(boot.cells[c].Get(BootstrapMetric::kBrierLabels).estimate));
  }
}

TEST(BootstrapTest, FrameCountsAreSeededUniformAndSumToN) {
  EXPECT_EQ(BootstrapFrameCounts(50, 3, 8), BootstrapFrameCounts(50, 3, 8));
  EXPECT_NE(BootstrapFrameCounts(50, 3, 8), BootstrapFrameCounts(50, 4, 8));
  EXPECT_NE(BootstrapFrameCounts(50, 3, 8), BootstrapFrameCounts(50, 3, 9));
  EXPECT_TRUE(BootstrapFrameCounts(0, 1, 0).empty());
  std::vector<double> mean(10, 0.0);
  constexpr int kResamples = 4000;
  for (int r = 0; r < kResamples; ++r) {
    const std::vector<int32_t> w = BootstrapFrameCounts(10, 1, r);
    int sum = 0;
    for (int f = 0; f < 10; ++f) {
      sum += w[f];
      mean[f] += w[f] / static_cast<double>(kResamples);
    }
    ASSERT_EQ(sum, 10);
  }
  // Each count is Binomial(10, 0.1): mean 1, standard error of the mean sqrt(0.9 / 4000) = 0.015.
  for (int f = 0; f < 10; ++f) EXPECT_NEAR(mean[f], 1.0, 0.08) << f;
}

TEST(BootstrapTest, DeterministicWithTheSeedAndThreadCountIndependent) {
  const std::vector<EvalFrame> frames = SmallFrames(12, 30);
  EvalOptions eval;
  BootstrapOptions b;
  b.num_resamples = 40;
  b.keep_samples = true;
  b.num_threads = 1;
  const BootstrapResult one = Bootstrap(frames, eval, b);
  b.num_threads = 2;
  const BootstrapResult two = Bootstrap(frames, eval, b);
  const BootstrapResult again = Bootstrap(frames, eval, b);
  b.seed = 2;
  const BootstrapResult other = Bootstrap(frames, eval, b);
  ASSERT_EQ(one.cells.size(), two.cells.size());
  bool any_differs = false;
  for (size_t c = 0; c < one.cells.size(); ++c) {
    for (int m = 0; m < kNumBootstrapMetrics; ++m) {
      const BootstrapInterval &x = one.cells[c].intervals[m], &y = two.cells[c].intervals[m],
                              &z = again.cells[c].intervals[m], &o = other.cells[c].intervals[m];
      ASSERT_EQ(x.samples.size(), 40u);
      for (size_t r = 0; r < x.samples.size(); ++r) {
        EXPECT_TRUE(Same(x.samples[r], y.samples[r]));
        EXPECT_TRUE(Same(y.samples[r], z.samples[r]));
      }
      EXPECT_TRUE(Same(x.lower, y.lower));
      EXPECT_TRUE(Same(x.upper, y.upper));
      EXPECT_EQ(x.num_defined, y.num_defined);
      for (size_t r = 0; r < x.samples.size(); ++r)
        any_differs |= !Same(x.samples[r], o.samples[r]);
    }
  }
  EXPECT_TRUE(any_differs);  // another seed, other resamples
}

// BCa by hand on the resamples 0, 1, ..., 99 (quantile level q reads 99 q).
TEST(BootstrapTest, BcaIntervalByHand) {
  std::vector<double> samples(100);
  for (int i = 0; i < 100; ++i) samples[i] = i;
  BootstrapInterval centred;
  centred.estimate = 49.5;  // half below: z0 = 0; a symmetric jackknife: a = 0
  FillBcaInterval(samples, {1.0, -1.0}, 0.95, false, &centred);
  EXPECT_EQ(centred.bias_correction, 0.0);
  EXPECT_EQ(centred.acceleration, 0.0);
  BootstrapInterval percentile;
  FillBootstrapInterval(samples, 0.95, false, &percentile);
  EXPECT_NEAR(centred.lower, percentile.lower, 1e-9);  // 2.475
  EXPECT_NEAR(centred.upper, percentile.upper, 1e-9);  // 96.525
  // 30 % below the estimate: z0 = Phi^-1(0.3) = -0.52440; the levels Phi(2 z0 -+ 1.95996) =
  // 0.0013116 and 0.81889 (Python's statistics.NormalDist).
  BootstrapInterval shifted;
  shifted.estimate = 29.5;
  FillBcaInterval(samples, {1.0, -1.0}, 0.95, true, &shifted);
  EXPECT_NEAR(shifted.bias_correction, -0.5244005127080407, 1e-12);
  EXPECT_NEAR(shifted.lower, 0.1298443998515399, 1e-9);
  EXPECT_NEAR(shifted.upper, 81.07062888311859, 1e-9);
  EXPECT_EQ(shifted.num_defined, 100);
  EXPECT_EQ(shifted.samples.size(), 100u);
  // The acceleration: jackknife 0, 0, 3: d = 1, 1, -2, a = -6 / (6 * 6^1.5).
  BootstrapInterval accelerated;
  accelerated.estimate = 49.5;
  FillBcaInterval(samples, {0.0, 0.0, 3.0, std::nan("")}, 0.95, false, &accelerated);
  EXPECT_NEAR(accelerated.acceleration, -1.0 / std::pow(6.0, 1.5), 1e-15);
  EXPECT_LT(accelerated.upper, percentile.upper);  // a < 0 pulls both bounds down
  // No interval: every resample above the estimate, or a NaN estimate, or no jackknife.
  BootstrapInterval none;
  none.estimate = -1;
  FillBcaInterval(samples, {1.0, -1.0}, 0.95, false, &none);
  EXPECT_TRUE(std::isnan(none.lower) && std::isnan(none.upper));
  none.estimate = 10;
  FillBcaInterval(samples, {1.0}, 0.95, false, &none);
  EXPECT_TRUE(std::isnan(none.lower));
}

TEST(BootstrapTest, JackknifeGroupsCoverEveryFrameOnce) {
  EXPECT_EQ(JackknifeGroupCount(10, 3), 3);
  EXPECT_EQ(JackknifeGroupCount(2, 100), 2);
  std::vector<int> left_out(10, 0);
  for (int g = 0; g < 3; ++g) {
    const std::vector<int32_t> w = JackknifeFrameCounts(10, 3, g);
    for (int f = 0; f < 10; ++f) left_out[f] += w[f] == 0;
  }
  EXPECT_EQ(left_out, std::vector<int>(10, 1));
  EXPECT_EQ(JackknifeFrameCounts(10, 3, 0), (std::vector<int32_t>{0, 0, 0, 1, 1, 1, 1, 1, 1, 1}));
  EXPECT_THROW(JackknifeFrameCounts(10, 3, 3), std::invalid_argument);
}

// BCa through Bootstrap: the same resamples as the percentile method, other bounds, with the
// correction and acceleration recorded; the paired difference of A against itself stays 0 or NaN.
TEST(BootstrapTest, BcaUsesTheSameResamples) {
  const std::vector<EvalFrame> frames = SmallFrames(12, 30);
  EvalOptions eval;
  eval.matcher = Matcher::kOptimal;
  BootstrapOptions b;
  b.num_resamples = 60;
  b.keep_samples = true;
  const BootstrapResult percentile = Bootstrap(frames, eval, b);
  b.method = BootstrapMethod::kBca;
  b.jackknife_groups = 6;
  const BootstrapResult bca = Bootstrap(frames, eval, b);
  EXPECT_EQ(bca.method, BootstrapMethod::kBca);
  int with_bounds = 0;
  for (size_t c = 0; c < bca.cells.size(); ++c) {
    const BootstrapInterval& x = percentile.cells[c].Get(BootstrapMetric::kApR40);
    const BootstrapInterval& y = bca.cells[c].Get(BootstrapMetric::kApR40);
    ASSERT_EQ(x.samples.size(), y.samples.size());
    for (size_t r = 0; r < x.samples.size(); ++r) EXPECT_TRUE(Same(x.samples[r], y.samples[r]));
    if (std::isnan(y.lower)) continue;
    EXPECT_LE(y.lower, y.upper);
    EXPECT_FALSE(std::isnan(y.bias_correction));
    EXPECT_FALSE(std::isnan(y.acceleration));
    ++with_bounds;
  }
  EXPECT_GT(with_bounds, 0);
}

TEST(BootstrapTest, PairedAVersusAIsExactlyZero) {
  const std::vector<EvalFrame> frames = SmallFrames(13, 30);
  EvalOptions eval;
  eval.matcher = Matcher::kOptimal;
  BootstrapOptions b;
  b.num_resamples = 50;
  const PairedBootstrapResult paired = PairedBootstrap(frames, frames, eval, b);
  int checked = 0;
  for (const BootstrapCell& c : paired.difference.cells) {
    for (const BootstrapMetric m : BootstrapMetrics(eval.matcher)) {
      const BootstrapInterval& d = c.Get(m);
      if (d.num_defined == 0) continue;
      EXPECT_EQ(d.estimate, 0.0);
      EXPECT_EQ(d.lower, 0.0);
      EXPECT_EQ(d.upper, 0.0);
      ++checked;
    }
  }
  EXPECT_GT(checked, 20);
}

TEST(BootstrapTest, PairedUsesTheSameResamplesForBoth) {
  const std::vector<EvalFrame> a = SmallFrames(14, 30);
  std::vector<EvalFrame> b = a;
  // B: every detection's score halved and a third of the detections dropped.
  for (EvalFrame& f : b) {
    std::vector<Object> kept;
    for (size_t j = 0; j < f.detections.size(); ++j) {
      if (j % 3 == 2) continue;
      kept.push_back(f.detections[j]);
      kept.back().score = *kept.back().score / 2;
    }
    f.detections = kept;
  }
  EvalOptions eval;
  BootstrapOptions options;
  options.num_resamples = 30;
  options.keep_samples = true;
  const PairedBootstrapResult paired = PairedBootstrap(a, b, eval, options);
  const BootstrapResult alone_a = Bootstrap(a, eval, options);
  const BootstrapResult alone_b = Bootstrap(b, eval, options);
  bool nonzero = false;
  for (size_t c = 0; c < paired.difference.cells.size(); ++c) {
    for (int m = 0; m < kNumBootstrapMetrics; ++m) {
      const BootstrapInterval& d = paired.difference.cells[c].intervals[m];
      const BootstrapInterval& x = alone_a.cells[c].intervals[m];
      const BootstrapInterval& y = alone_b.cells[c].intervals[m];
      EXPECT_TRUE(Same(paired.a.cells[c].intervals[m].lower, x.lower));
      EXPECT_TRUE(Same(paired.b.cells[c].intervals[m].upper, y.upper));
      EXPECT_TRUE(Same(d.estimate, x.estimate - y.estimate));
      for (size_t r = 0; r < d.samples.size(); ++r) {
        EXPECT_TRUE(Same(d.samples[r], x.samples[r] - y.samples[r]));
        nonzero |= d.samples[r] != 0 && !std::isnan(d.samples[r]);
      }
      if (d.num_defined > 0) {
        EXPECT_LE(d.lower, d.upper);
      }
    }
  }
  EXPECT_TRUE(nonzero);
}

TEST(BootstrapTest, PairedRefusesOtherFrames) {
  const std::vector<EvalFrame> a = SmallFrames(15, 5);
  std::vector<EvalFrame> b = a;
  b[3].id = "other";
  BootstrapOptions options;
  options.num_resamples = 2;
  EXPECT_THROW(PairedBootstrap(a, b, EvalOptions(), options), std::invalid_argument);
  b.pop_back();
  EXPECT_THROW(PairedBootstrap(a, b, EvalOptions(), options), std::invalid_argument);
}

TEST(BootstrapTest, OptionsCheckAndNames) {
  BootstrapOptions o;
  EXPECT_NO_THROW(o.Check());
  o.num_resamples = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.num_resamples = kMaxBootstrapResamples + 1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.num_resamples = 10;
  o.confidence = 1.0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.confidence = 0.0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  for (int m = 0; m < kNumBootstrapMetrics; ++m) {
    const auto metric = static_cast<BootstrapMetric>(m);
    EXPECT_EQ(ParseBootstrapMetric(BootstrapMetricName(metric)), metric);
  }
  EXPECT_FALSE(ParseBootstrapMetric("ap").has_value());
  EXPECT_EQ(BootstrapMetrics(Matcher::kKitti).size(), 5u);
  EXPECT_EQ(BootstrapMetrics(Matcher::kOptimal).size(), 6u);
}

}  // namespace
}  // namespace stereodet
