// The whole evaluation: every class x overlap kind x difficulty, with the chosen matcher.
//
//   std::vector<EvalFrame> frames = ...;           // labels + detections per frame
//   EvalOptions options;                           // defaults: KITTI matcher, Car/Ped/Cyc,
//   2D/BEV/3D EvalResult result = Evaluate(frames, options);
#ifndef STEREODET_EVAL_EVALUATOR_H_
#define STEREODET_EVAL_EVALUATOR_H_

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/curves.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/filter.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/score_metrics.h"

namespace stereodet {

// The PR curve and its summaries under a filter (percent; aos_* NaN where AOS is not computed,
// apl_* NaN but in the LET kinds).
// KITTI matcher: the devkit's arithmetic (41 slots, envelope) at the devkit thresholds (naive:
// those of the struck set; stable: those of the unfiltered set). Optimal / VOC: exact at every
// score.
struct FilteredCurve {
  std::vector<CurvePoint> curve;
  double ap_r40 = 0.0, ap_r11 = 0.0, ap_voc = 0.0;
  double aos_r40 = 0.0, aos_r11 = 0.0;
  double apl_r40 = std::numeric_limits<double>::quiet_NaN();
  double apl_r11 = std::numeric_limits<double>::quiet_NaN();
};

// TP/FP/FN under a filter at the operating threshold, and the curves, in both modes.
struct FilteredStats {
  OperatingPoint naive;
  OperatingPoint stable;
  FilteredCurve naive_curve;
  FilteredCurve stable_curve;
};

// What one detection or label counts as in one class x overlap kind x difficulty at the operating
// point (EvalOptions::score_threshold), as the matcher associated them (EvalOptions::keep_records).
// A true positive is one row holding both sides; every other row holds one side:
//   kTp                          detection + label, the matched pair;
//   kFp, kIgnored, kDontCare     a detection alone (kIgnored: an ignored detection, e.g. lower than
//                                the difficulty's minimum height, or one on an ignored label);
//   kFn, kIgnored                a label alone (kIgnored: a neighbour class, a label that does not
//                                meet the difficulty, or one excused by an ignored detection).
// Detections below the operating point and those of other classes that take no part
// (Outcome::kNone) have no row. Summing the rows gives ClassResult::at_threshold and the Brier
// scores exactly.
struct MatchRecord {
  int32_t frame = -1;      // index into the evaluated frames
  int32_t detection = -1;  // index into the frame's detections (file order); -1 for a label alone
  int32_t label = -1;      // index into the frame's labels (file order); -1 for a detection alone
  Outcome outcome = Outcome::kNone;
  // The label is valid at the cell's difficulty (class, not a neighbour, meets the difficulty): one
  // term of the Brier score over labels, 1 unless kTp, also when excused by an ignored detection.
  bool label_valid = false;
  // kTp: the overlap that decided the match. Otherwise the largest overlap of the row's object with
  // the other side: for a detection, with any label of the class or its neighbours; for a label,
  // with any detection of the class at the operating point (0 when there is none). Same overlap
  // kind and definition as the matching (MatchOverlap: KittiOverlap, or LET-IoU in the LET kinds).
  double iou = 0.0;
};

// One bin of a breakdown of a cell (breakdown.h: what counts in a bin), from the cell's matching.
struct BreakdownBin {
  BreakdownAxis axis = BreakdownAxis::kDistance;
  double lower = 0.0, upper = 0.0;  // the bin [lower, upper), in the axis' unit
  int64_t num_valid_labels = 0;     // the cell's valid labels in the bin
  OperatingPoint at_threshold;      // at EvalOptions::score_threshold
  // Its curve: KITTI matcher, the devkit's arithmetic at the cell's thresholds; optimal / VOC,
  // exact at every score (as FilteredStats::stable_curve).
  FilteredCurve curve;
  BrierScores brier;  // NaN where the cell's are (EvalResult::probability_metrics)
  // Reliability, ECE and LaECE of the bin's counted detections (a pair in its label's bin, a FP
  // where its own value is): calibration per distance, height, ... bin. NaN as the cell's.
  CalibrationResult calibration;
  // With EvalOptions::breakdown_naive: the bin evaluated on its own, its labels and detections
  // struck outside it before matching (the naive per-bin recomputation: a pair across an edge
  // becomes a FN in one bin and a FP in the other, and a detection can find another label than in
  // the whole cell's matching). Its curve as FilteredStats::naive_curve's.
  struct Naive {
    int64_t num_valid_labels = 0;
    OperatingPoint at_threshold;
    FilteredCurve curve;
  };
  std::optional<Naive> naive;
};

// One class x overlap kind x difficulty.
struct ClassResult {
  std::string class_name;
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  double min_overlap = 0.5;
  // False when the devkit would skip this class and overlap kind (no detection of it with a valid
  // box of that kind; see EvalOptions::require_detections). Nothing else is filled then.
  bool evaluated = true;

  int64_t num_valid_labels = 0;  // labels counted at this difficulty (KITTI's n_gt)
  int64_t num_detections = 0;    // detections of the class

  // Percent. ap_voc is NaN for the KITTI matcher (its curve has only 41 points); aos_* are NaN when
  // AOS is not computed (BEV/3D and the LET kinds, or a detection with alpha = -10, for every
  // matcher). apl_* (LET-3D-APL, docs/metrics.md "LET-3D-AP"): the LET kinds only, NaN otherwise;
  // AP with each true positive counted as its longitudinal affinity in the precision, computed as
  // AOS is with the affinity in place of the orientation similarity (so the curve's
  // CurvePoint::orientation is the affinity-weighted precision in a LET cell).
  double ap_r40 = 0.0, ap_r11 = 0.0, ap_voc = 0.0;
  double aos_r40 = 0.0, aos_r11 = 0.0;
  bool has_aos = false;
  double apl_r40 = std::numeric_limits<double>::quiet_NaN();
  double apl_r11 = std::numeric_limits<double>::quiet_NaN();
  bool has_apl = false;

  // KITTI: one point per devkit threshold (<= 41); optimal/VOC: one per distinct score (exact).
  std::vector<CurvePoint> curve;
  // KITTI matcher only: the devkit's 41-slot arrays after the envelope, and its thresholds;
  // kitti_aos of a LET cell is its APL's weighted precision (kitti_apl), kitti_aos then empty.
  std::vector<double> kitti_precision, kitti_aos, kitti_apl, kitti_thresholds;

  OperatingPoint at_threshold;            // at EvalOptions::score_threshold
  OperatingPoint best_f1;                 // over the curve's points
  std::optional<FilteredStats> filtered;  // when EvalOptions::filter has conditions
  // With EvalOptions::breakdowns: every breakdown's bins, in the options' order, bins ascending.
  std::vector<BreakdownBin> breakdown;

  BrierScores brier;
  CalibrationResult calibration;
  std::vector<DistanceBin> localization;

  // With EvalOptions::keep_records: by frame, then detections in file order, then the labels
  // without a detection in file order.
  std::vector<MatchRecord> records;
};

// With this many valid labels or fewer in a cell, the devkit's AP_R40 (KITTI matcher) is capped
// at (TP - 1) / 40: every TP score becomes one of its thresholds, so at most TP of its 41 slots
// are filled (26 perfect detections of 27 labels give 62.5). Reports mark such cells.
inline constexpr int64_t kSmallSampleLabels = 40;
inline bool IsSmallSample(const ClassResult& r) {
  return r.evaluated && r.num_valid_labels <= kSmallSampleLabels;
}

// The raw scores of every detection (any class) of the evaluated frames.
struct ScoreSummary {
  int64_t num_scores = 0;
  int64_t num_outside_unit = 0;             // scores < 0 or > 1
  double min_score = 0.0, max_score = 0.0;  // NaN when there is no detection
};

struct EvalResult {
  int64_t num_frames = 0;
  bool aos_computed = false;  // false when a detection has alpha = -10 (devkit rule) or disabled
  ScoreSummary scores;
  // False when a score is outside [0, 1] and EvalOptions::score_transform is kNone: the scores are
  // not probabilities, and every cell's Brier scores and ECE are left out (NaN).
  bool probability_metrics = true;
  std::vector<ClassResult>
      results;           // class-major, then overlap kind, then difficulty (options order)
  double seconds = 0.0;  // wall time of Evaluate()

  // The result for a class / kind / difficulty, or nullptr.
  const ClassResult* Find(const std::string& class_name, OverlapKind metric,
                          Difficulty difficulty) const;
};

// Requires: options.Check() passes; every detection has a score.
EvalResult Evaluate(const std::vector<EvalFrame>& frames, const EvalOptions& options);

// Filter sweep (the paper's filter figure): for each value of `bound` from `from` to `to` by
// `step`, the operating-point statistics under the naive and the stable filter.
struct SweepRow {
  std::string class_name;
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  double value = 0.0;
  FilteredStats stats;
};
std::vector<SweepRow> FilterSweep(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                                  FilterBound bound, double from, double to, double step);

}  // namespace stereodet

#endif  // STEREODET_EVAL_EVALUATOR_H_
