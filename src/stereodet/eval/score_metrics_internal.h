// Internal to the eval module: the accumulation of score_metrics.h's metrics over many frames.
#ifndef STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_
#define STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_

#include <cstdint>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/score_metrics.h"

namespace stereodet {

// The scores are not probabilities (see EvalResult::probability_metrics): every Brier mean, or the
// ECE and the bins' mean score and TP fraction, set to NaN (the term counts and bin counts stay).
BrierScores WithoutProbabilities(BrierScores brier);
CalibrationResult WithoutProbabilities(CalibrationResult calibration);

// Accumulates the operating-point metrics of many frames' associations; Brier(), Calibration() and
// Localization() then give them.
class ScoreMetricsAccumulator {
 public:
  // Brier scores and calibration use ApplyScoreTransform(transform, score).
  ScoreMetricsAccumulator(int calibration_bins, double distance_bin_m, double max_distance_m,
                          ScoreTransform transform = ScoreTransform::kNone);

  // `association` is that of `class_frame` at `difficulty` (which decides the valid labels). With
  // `selection`, only what it keeps (a breakdown bin's pairs, labels and detections) adds terms.
  void Add(const EvalFrame& frame, const ClassFrame& class_frame,
           const FrameAssociation& association, Difficulty difficulty,
           const StableSelection* selection = nullptr);

  BrierScores Brier() const;  // means
  CalibrationResult Calibration() const;
  std::vector<DistanceBin> Localization() const;  // bins [0, w), [w, 2w), ... up to max_distance_m

 private:
  BrierScores brier_sums_;
  std::vector<int64_t> bin_count_, bin_tp_;
  std::vector<double> bin_score_sum_;
  int64_t out_of_range_ = 0;
  double distance_bin_m_, max_distance_m_;
  ScoreTransform transform_;
  std::vector<std::vector<double>> centre_errors_, depth_errors_;
};

// Quantile q in [0, 1] of `values` with linear interpolation (NumPy's default); NaN if empty.
double Quantile(std::vector<double> values, double q);

}  // namespace stereodet

#endif  // STEREODET_EVAL_SCORE_METRICS_INTERNAL_H_
