// Fitting score calibrators (kitti/score_calibration.h) on one split: `stereodet calibrate --fit`.
// Each detection of a class that the matcher calls a true positive is a 1, each false positive a 0
// (detections it ignores or excuses, in DontCare regions or on ignored labels, take no part), and
// a calibrator per class maps the scores to the probability of a 1. Misses are not detections and
// cannot be calibrated: a calibrated score is the precision of a detection of that score, never the
// recall (docs/metrics.md, "Calibrators" and "Calibration").
#ifndef STEREODET_EVAL_CALIBRATION_FIT_H_
#define STEREODET_EVAL_CALIBRATION_FIT_H_

#include <cstdint>
#include <string>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/kitti/score_calibration.h"

namespace stereodet {

struct CalibrationFitOptions {
  // The matching that makes the targets: its classes (each gets a calibrator), matcher, compat,
  // LET tolerance and overlap set; exactly one overlap kind and one difficulty (defaults: 2D, which
  // every detector family writes, Moderate, the optimal matcher). score_transform kSigmoid: the
  // scores are logits (the calibration file records it).
  EvalOptions eval = DefaultEval();
  CalibrationMethod method = CalibrationMethod::kPlatt;
  // A class that cannot be fitted (no detection to fit on, no true or no false positive, or a
  // fit the method refuses, e.g. Platt's slope <= 0) is listed in ScoreCalibration::unfitted with
  // why, instead of an error.
  bool skip_unfittable = false;

  static EvalOptions DefaultEval();
  // Throws std::invalid_argument on several or no overlap kinds or difficulties, or what
  // EvalOptions::Check refuses.
  void Check() const;
};

// One class's fit and what it did on the fitted detections themselves (in-sample: a held-out
// split says what it does, `eval --calibration`).
struct ClassCalibrationFit {
  std::string class_name;
  int64_t num_tp = 0, num_fp = 0;
  bool fitted = true;  // false: CalibrationFitOptions::skip_unfittable left it out (the rest 0)
  // Over the fitted detections (a TP 1, a FP 0): mean squared error and mean negative log
  // likelihood of the scores before (as probabilities: the scores themselves, or their sigmoid for
  // logits) and after calibration.
  double brier_before = 0.0, brier_after = 0.0;
  double nll_before = 0.0, nll_after = 0.0;
};

struct CalibrationFit {
  ScoreCalibration calibration;
  std::vector<ClassCalibrationFit> classes;  // EvalOptions::classes' order
};

// Fits a calibrator for every class of options.eval.classes. Throws std::invalid_argument naming
// the class when it has no true positive or no false positive in the frames (nothing to fit), and
// for temperature and Platt when the scores rank the false positives above the true positives (a
// fitted slope <= 0). fitted_on records the frames, matcher, metric, difficulty, thresholds and
// counts.
CalibrationFit FitScoreCalibration(const std::vector<EvalFrame>& frames,
                                   const CalibrationFitOptions& options);

// The three fits on (x, target) pairs, for the tests and scripts/calibration_reference_cases.py.
// Temperature: x are logits; minimises the negative log likelihood of sigmoid(x / T) over T > 0.
ScoreCalibrator FitTemperature(const std::vector<double>& x, const std::vector<uint8_t>& targets);
// Platt: x are logits; minimises the negative log likelihood of sigmoid(a x + b) against Platt's
// smoothed targets ((N+ + 1) / (N+ + 2) for a 1, 1 / (N- + 2) for a 0), as scikit-learn's
// CalibratedClassifierCV(method="sigmoid") does.
ScoreCalibrator FitPlatt(const std::vector<double>& x, const std::vector<uint8_t>& targets);
// Isotonic: x are the raw scores; the non-decreasing least-squares fit (pool adjacent violators,
// equal x averaged first), kept at the points where it changes, as scikit-learn's
// IsotonicRegression(out_of_bounds="clip").
ScoreCalibrator FitIsotonic(const std::vector<double>& x, const std::vector<uint8_t>& targets);

}  // namespace stereodet

#endif  // STEREODET_EVAL_CALIBRATION_FIT_H_
