// Bootstrap confidence intervals over frames, exact for each resample.
//
// A resample draws N of the N frames with replacement: a multiset of frames, each frame f taken
// w_f times (BootstrapFrameCounts). Association is per frame, so every metric of a resample is a
// function of per-frame statistics weighted by w_f; Bootstrap computes them once per frame and
// then, per resample, the metrics exactly as Evaluate would on the resampled frame list (each frame
// f repeated w_f times), without matching anything again:
//   - KITTI matcher: the devkit's pass 1 TP scores of each frame (weighted, so the thresholds are
//     the resample's own: getThresholds on its TP scores and n_gt), and each frame's pass 2 counts
//     as a step function of the threshold (it changes only at the frame's own scores), summed at
//     the resample's thresholds; then the devkit's 41-slot arithmetic (AP_R40, AP_R11);
//   - optimal / VOC matchers: each frame's curve events (BuildCurve's), weighted: AP_R40, AP_R11
//     and the every-point AP of the exact curve;
//   - Brier scores (over labels, detections, all) at the operating point: each frame's terms, in
//     Evaluate's order.
// AP is bit-identical to Evaluate's on the materialised frame list, Brier too (the test
// BootstrapTest.MatchesEvaluateOnEveryResample says so). AOS, calibration, localization and the
// filtered statistics are not resampled.
//
// With EvalOptions::breakdowns, every bin of every cell (ClassResult::breakdown) gets the same
// intervals, again exactly what Evaluate gives for the bin on the materialised frame list
// (BootstrapTest.BreakdownBinsMatchEvaluateOnEveryResample*): the bin's counts are its
// StableSelection's tally of the cell's association, stored per frame as above, at the same
// thresholds as the cell's (KITTI: the resample's own, from the whole cell's TP scores), with a
// bin's empty threshold slot at precision 0 and NaN AP for a bin without a valid label
// (breakdown.h, evaluator.cc). PairedBootstrap resamples the bins too (A - B per bin).
//
//   BootstrapOptions bootstrap;                   // 1000 resamples, seed 1, 95 %
//   BootstrapResult b = Bootstrap(frames, eval_options, bootstrap);
//   const BootstrapInterval& ap = b.Find("Car", OverlapKind::k3D, Difficulty::kModerate)
//                                     ->Get(BootstrapMetric::kApR40);   // ap.lower, ap.upper
//
// PairedBootstrap resamples two detection sets of the same frames with the same frame counts, so
// that the difference A - B of each metric gets its own interval (A vs A: exactly [0, 0]).
#ifndef STEREODET_EVAL_BOOTSTRAP_H_
#define STEREODET_EVAL_BOOTSTRAP_H_

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"

namespace stereodet {

// At most this many resamples: Bootstrap keeps every resample's values until the end, 48 bytes per
// cell or breakdown bin and resample (27 cells x 10^5 resamples: 130 MB; with 3 bins per cell, 4x).
inline constexpr int kMaxBootstrapResamples = 100000;

// How an interval is read from the resamples.
enum class BootstrapMethod {
  kPercentile,  // the (1 - c) / 2 and (1 + c) / 2 quantiles of the resamples
  // Efron's bias-corrected and accelerated interval: quantiles moved by the bias correction z0 =
  // Phi^-1(share of resamples below the estimate, ties counting half) and the acceleration a
  // from a grouped jackknife (BootstrapOptions::jackknife_groups). Corrects the percentile
  // interval of a statistic whose resamples are biased (AP's are: docs/metrics.md).
  kBca,
};
const char* BootstrapMethodName(BootstrapMethod method);   // "percentile", "bca"
const char* BootstrapMethodTitle(BootstrapMethod method);  // "percentile", "BCa" (printouts)
std::optional<BootstrapMethod> ParseBootstrapMethod(std::string_view text);

struct BootstrapOptions {
  // Resamples, in [1, kMaxBootstrapResamples]; 1000 is the usual choice for 95 % intervals.
  int num_resamples = 1000;
  // Resample r's frame counts depend on (seed, r) only: the same seed gives the same intervals on
  // any number of threads.
  uint64_t seed = 1;
  // Two-sided percentile interval: the (1 - c) / 2 and (1 + c) / 2 quantiles (linear
  // interpolation, NumPy's default) of the resamples' values. In (0, 1).
  double confidence = 0.95;
  BootstrapMethod method = BootstrapMethod::kPercentile;
  // kBca's acceleration: the frames (images) cut into this many contiguous groups, each left out
  // once (a grouped jackknife: G more evaluations, not N); at least 2. With N frames or fewer, one
  // frame per group (the ordinary jackknife).
  int jackknife_groups = 100;
  // Keep every resample's value (BootstrapInterval::samples), for tests and plots.
  bool keep_samples = false;
  int num_threads = 0;  // 0 = all hardware threads; the result does not depend on it

  // Throws std::invalid_argument for num_resamples outside [1, kMaxBootstrapResamples], or
  // confidence outside (0, 1).
  void Check() const;
};

// The metrics resampled, in the order of BootstrapCell::intervals.
enum class BootstrapMetric {
  kApR40 = 0,        // ClassResult::ap_r40 (percent)
  kApR11,            // ClassResult::ap_r11 (percent)
  kApVoc,            // ClassResult::ap_voc (percent; optimal and VOC matchers only, else NaN)
  kBrierLabels,      // ClassResult::brier.over_labels
  kBrierDetections,  // ClassResult::brier.over_detections
  kBrierAll,         // ClassResult::brier.over_all
};
inline constexpr int kNumBootstrapMetrics = 6;
// "ap_r40", "ap_r11", "ap_voc", "brier_labels", "brier_detections", "brier_all".
const char* BootstrapMetricName(BootstrapMetric metric);
std::optional<BootstrapMetric> ParseBootstrapMetric(std::string_view text);
// The metrics `matcher` has (kApVoc only for the optimal and VOC matchers), in enum order.
std::vector<BootstrapMetric> BootstrapMetrics(Matcher matcher);

struct BootstrapInterval {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  // On the frames as given (every frame once): the ClassResult's value.
  double estimate = kNaN;
  // The percentile interval over the resamples where the metric is a number (NaN when none is).
  double lower = kNaN, upper = kNaN;
  // Resamples where the metric is a number: a resample without a valid label (Brier over labels),
  // without a counted detection (over detections), without an evaluable detection of the class
  // (EvalOptions::require_detections), or with a score outside [0, 1] and no score transform
  // (Brier) gives NaN and is left out.
  int64_t num_defined = 0;
  // With BootstrapOptions::keep_samples: resample r's value, NaN where undefined.
  std::vector<double> samples;
  // kBca: the bias correction z0 and the acceleration a the bounds were read with (NaN otherwise,
  // or where the interval is NaN).
  double bias_correction = kNaN;
  double acceleration = kNaN;
};

// One bin of a cell's breakdown (BreakdownBin), in ClassResult::breakdown's order.
struct BootstrapBin {
  BreakdownAxis axis = BreakdownAxis::kDistance;
  double lower = 0.0, upper = 0.0;  // the bin [lower, upper), in the axis' unit
  // By BootstrapMetric, as BreakdownBin's figures: AP NaN in a resample where the bin holds no
  // valid label (or the cell is not evaluated), Brier NaN where it has no term.
  std::array<BootstrapInterval, kNumBootstrapMetrics> intervals;

  const BootstrapInterval& Get(BootstrapMetric m) const { return intervals[static_cast<int>(m)]; }
};

// One class x overlap kind x difficulty, in Evaluate's order.
struct BootstrapCell {
  std::string class_name;
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  // As ClassResult::evaluated on the frames as given; false: every interval NaN.
  bool evaluated = true;
  std::array<BootstrapInterval, kNumBootstrapMetrics> intervals;  // by BootstrapMetric
  // With EvalOptions::breakdowns: every breakdown's bins, in the options' order, bins ascending, as
  // ClassResult::breakdown; empty for a cell that is not evaluated.
  std::vector<BootstrapBin> breakdown;

  const BootstrapInterval& Get(BootstrapMetric m) const { return intervals[static_cast<int>(m)]; }
};

struct BootstrapResult {
  int num_resamples = 0;
  uint64_t seed = 0;
  double confidence = 0.0;
  Matcher matcher = Matcher::kKitti;
  BootstrapMethod method = BootstrapMethod::kPercentile;  // how the bounds were read
  int64_t num_frames = 0;
  std::vector<BootstrapCell> cells;  // class-major, then overlap kind, then difficulty
  double seconds = 0.0;              // wall time

  // The cell for a class (case-insensitive) / kind / difficulty, or nullptr.
  const BootstrapCell* Find(const std::string& class_name, OverlapKind metric,
                            Difficulty difficulty) const;
};

// Frame f's multiplicity in resample r: N draws of a frame index, uniform, with replacement, from
// a SplitMix64 stream seeded by (seed, r) (unbiased: a draw is
// repeated when it falls in the incomplete last block of 2^64 mod N values). Sums to num_frames.
std::vector<int32_t> BootstrapFrameCounts(int64_t num_frames, uint64_t seed, int64_t resample);

// interval->lower / upper: the percentile interval (`confidence`, NumPy's linear quantiles) of the
// numbers among `samples` (NaN are left out; num_defined counts the others); with keep_samples,
// interval->samples = samples. The estimate is left as it is.
void FillBootstrapInterval(const std::vector<double>& samples, double confidence, bool keep_samples,
                           BootstrapInterval* interval);

// The BCa interval instead (BootstrapMethod::kBca), from interval->estimate (set it first), the
// resamples and the jackknife's leave-one-group-out values (NaN ones left out): with alpha =
// (1 - confidence) / 2, z0 = Phi^-1((#{s < estimate} + #{s == estimate} / 2) / n), a =
// sum(d^3) / (6 (sum(d^2))^1.5) with d = mean(jackknife) - jackknife, the bounds are the
// quantiles at Phi(z0 + (z0 + z) / (1 - a (z0 + z))) for z = Phi^-1(alpha), Phi^-1(1 - alpha).
// NaN bounds when the estimate is NaN, no resample is defined, every resample lies on one side of
// the estimate (z0 infinite), or fewer than 2 jackknife values are (a = 0 when they are all equal).
void FillBcaInterval(const std::vector<double>& samples, const std::vector<double>& jackknife,
                     double confidence, bool keep_samples, BootstrapInterval* interval);

// The interval of options.method from the resamples (and, for kBca, the jackknife's values):
// FillBootstrapInterval or FillBcaInterval with options.confidence and options.keep_samples.
void FillInterval(const BootstrapOptions& options, const std::vector<double>& samples,
                  const std::vector<double>& jackknife, BootstrapInterval* interval);

// Frame f's multiplicity in the jackknife's group g: 1, or 0 for the frames of group g, the
// groups being min(groups, num_frames) contiguous runs of floor or ceil(num_frames / groups)
// frames. Requires 0 <= g < min(groups, num_frames).
std::vector<int32_t> JackknifeFrameCounts(int64_t num_frames, int groups, int g);
int JackknifeGroupCount(int64_t num_frames, int groups);  // min(groups, num_frames)

// Intervals of every cell of Evaluate(frames, eval) (see the file comment). eval.filter is not
// applied to the resampled metrics (they are the unfiltered ones). Requires: eval.Check() and
// bootstrap.Check() pass; every detection has a score.
BootstrapResult Bootstrap(const std::vector<EvalFrame>& frames, const EvalOptions& eval,
                          const BootstrapOptions& bootstrap);

// Two detection sets of the same frames (same ids, same order; the labels of `a` and `b` should be
// the same), resampled with the same frame counts. `difference` holds, per cell and metric, the
// estimate A - B and the interval of the resamples' A - B (over the resamples where both are
// numbers), and with eval.breakdowns the same for every bin of every cell (BootstrapCell::
// breakdown, in A's cells); `a` and `b` are Bootstrap's results for each. A cell evaluated in only
// one of them has a NaN difference, and so have its bins.
struct PairedBootstrapResult {
  BootstrapResult a, b, difference;
};
// Throws std::invalid_argument when the frame lists differ in length or in an id.
PairedBootstrapResult PairedBootstrap(const std::vector<EvalFrame>& a,
                                      const std::vector<EvalFrame>& b, const EvalOptions& eval,
                                      const BootstrapOptions& bootstrap);

}  // namespace stereodet

#endif  // STEREODET_EVAL_BOOTSTRAP_H_
