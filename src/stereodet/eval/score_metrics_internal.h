// Internal to the eval module: the accumulation of score_metrics.h's metrics over many frames.
#ifndef STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_
#define STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/score_metrics.h"
#include "stereodet/eval/selection_mask_internal.h"

namespace stereodet {

// The scores are not probabilities (see EvalResult::probability_metrics): every Brier mean, or the
// ECE and the bins' mean score and TP fraction, set to NaN (the term counts and bin counts stay).
BrierScores WithoutProbabilities(BrierScores brier);
CalibrationResult WithoutProbabilities(CalibrationResult calibration);

// Keeps every label and detection: ForEachBrierTerm without a selection.
struct KeepEverything {
  bool KeepsLabel(int) const { return true; }
  bool KeepsDetection(int) const { return true; }
  bool KeepsPair(int, int) const { return true; }
};

// The Brier terms of one frame's association `a` at the operating point, in the order Evaluate
// sums them (ScoreMetricsAccumulator::Add and the bootstrap's per-frame terms both come from here):
// first the labels in order, `on_label(term, i, j)`: a TP pair's label (1 - s)^2 with its detection
// j, a valid label alone (FN, or excused by an ignored detection) 1 with j = -1; then the TP and FP
// detections in order, `on_detection(s, outcome, j)` with s the transformed score. Only what
// `keeps` keeps (KeepEverything, or a selection's MaskView): a pair by KeepsPair(i, j), a lone
// label by KeepsLabel(i), an FP by KeepsDetection(j).
template <typename Keeps, typename OnLabel, typename OnDetection>
void ForEachBrierTerm(const ClassFrame& cf, const FrameAssociation& a, Difficulty difficulty,
                      ScoreTransform transform, const Keeps& keeps, OnLabel on_label,
                      OnDetection on_detection) {
  for (int i = 0; i < cf.num_labels(); ++i) {
    if (a.label_outcome[i] == Outcome::kTp) {
      const int j = a.label_det[i];
      if (!keeps.KeepsPair(i, j)) continue;
      const double s = ApplyScoreTransform(transform, cf.det_score[j]);
      on_label((1 - s) * (1 - s), i, j);
    } else if (cf.LabelValid(i, difficulty) && keeps.KeepsLabel(i)) {
      // FN, or excused by an ignored (too low) detection: the label's term is there all the same,
      // so that every detector is scored over the same labels.
      on_label(1.0, i, -1);
    }
  }
  for (int j = 0; j < cf.num_dets(); ++j) {
    const Outcome o = a.det_outcome[j];
    if (o != Outcome::kTp && o != Outcome::kFp) continue;
    if (o == Outcome::kTp ? !keeps.KeepsPair(a.det_label[j], j) : !keeps.KeepsDetection(j)) {
      continue;
    }
    on_detection(ApplyScoreTransform(transform, cf.det_score[j]), o, j);
  }
}

// Accumulates the operating-point metrics of many frames' associations; Brier(), Calibration() and
// Localization() then give them.
class ScoreMetricsAccumulator {
 public:
  // Brier scores and calibration use ApplyScoreTransform(transform, score).
  ScoreMetricsAccumulator(int calibration_bins, double distance_bin_m, double max_distance_m,
                          ScoreTransform transform = ScoreTransform::kNone);

  // A detection's D-ECE bin (DeceOptions::bins, score first, row-major), or why it has none.
  struct DeceCell {
    enum State : uint8_t { kOff, kNoBox, kIn } state = kOff;
    bool outside = false;  // a feature was outside [0, 1] (clamped into the end bins)
    size_t index = 0;
  };
  // The D-ECE cell of each detection of `class_frame` (from its transformed score and 2D box),
  // written to out[0, num_dets): for Add and AddToBins to reuse across difficulties and bins (a
  // detection's box is far in memory; reading it once per cell instead of once per accumulator
  // was a tenth of a breakdown's time).
  void DeceCells(const EvalFrame& frame, const ClassFrame& class_frame, DeceCell* out) const;

  // `association` is that of `class_frame` at `difficulty` (which decides the valid labels). With
  // `selection`, only what it keeps (a breakdown bin's pairs, labels and detections) adds terms.
  // `dece_cells`: DeceCells of this frame by an accumulator with the same options, or null.
  void Add(const EvalFrame& frame, const ClassFrame& class_frame,
           const FrameAssociation& association, Difficulty difficulty,
           const StableSelection* selection = nullptr, const DeceCell* dece_cells = nullptr);

  // One term of each kind, for callers with their own association (COCO mode): a valid label's
  // (1 - s)^2 for its TP detection's transformed score s, or 1 without one; a counted detection
  // (TP or FP) with its transformed score. Add() is made of these.
  void AddLabelTerm(double term);
  // `overlap`: a TP's overlap with its label, for LaECE (NaN: unknown, LaECE then NaN). `box`: the
  // detection's 2D box, for D-ECE (null: unknown, D-ECE then NaN).
  void AddDetectionTerm(double s, bool tp, double overlap = kUnknownOverlap,
                        const Box2D* box = nullptr);
  // Add of one frame for several selections at once (a cell's breakdown bins: the first `n_s` of
  // `masks`): accs[s] gets the terms bin s keeps, in the order Add would add them under bin s's
  // selection, each term computed once for all (`dece_cells` as Add's). The localization errors are
  // not collected (a bin reports none). Precondition: the accumulators have the same transform and
  // D-ECE options.
  static void AddToBins(const EvalFrame& frame, const ClassFrame& class_frame,
                        const FrameAssociation& association, Difficulty difficulty,
                        const BinMasks& masks, size_t n_s, ScoreMetricsAccumulator* accs,
                        const DeceCell* dece_cells = nullptr);
  // Turns D-ECE on (off by default: COCO mode has no image size).
  void EnableDece(const DeceOptions& options);
  static constexpr double kUnknownOverlap = std::numeric_limits<double>::quiet_NaN();

  BrierScores Brier() const;  // means
  CalibrationResult Calibration() const;
  std::vector<DistanceBin> Localization() const;  // bins [0, w), [w, 2w), ... up to max_distance_m

 private:
  DeceCell DeceCellOf(double s, const Box2D* box) const;
  // Detection j's cell: dece_cells[j] where given (DeceCells), else from its box.
  DeceCell DeceCellOf(const EvalFrame& frame, const ClassFrame& cf, int j, double s,
                      const DeceCell* dece_cells) const;
  void AddDetectionTermIn(double s, bool tp, double overlap, const DeceCell& cell);

  template <typename Keeps>
  void AddKept(const EvalFrame& frame, const ClassFrame& class_frame,
               const FrameAssociation& association, Difficulty difficulty, const Keeps& keeps,
               const DeceCell* dece_cells);

  BrierScores brier_sums_;
  std::vector<int64_t> bin_count_, bin_tp_;
  std::vector<double> bin_score_sum_;
  std::vector<double> bin_iou_sum_;  // TPs' overlaps (FPs add 0): LaECE
  bool overlaps_known_ = true;
  int64_t out_of_range_ = 0;
  // D-ECE: per joint bin (DeceOptions::bins, score first, row-major) the detections, their score
  // sum and TPs; empty when off.
  DeceOptions dece_;
  std::array<double, 5> dece_step_{};  // 1 / dece_.bins[d]: the width of a bin of feature d
  std::vector<int64_t> dece_count_, dece_tp_;
  std::vector<double> dece_score_sum_;
  bool boxes_known_ = true;
  int64_t dece_outside_ = 0;
  double distance_bin_m_, max_distance_m_;
  ScoreTransform transform_;
  std::vector<std::vector<double>> centre_errors_, depth_errors_;
};

// Quantile q in [0, 1] of `values` with linear interpolation (NumPy's default); NaN if empty.
double Quantile(std::vector<double> values, double q);

}  // namespace stereodet

#endif  // STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_
