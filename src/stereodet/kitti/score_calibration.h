// Score calibrators: per-class maps from a detector's scores to calibrated probabilities
// (temperature scaling, Platt scaling, isotonic regression), fitted on one split by `stereodet
// calibrate --fit` (eval/calibration_fit.h) and applied to detections by `stereodet eval
// --calibration`. Here: the calibrators, applying them, and their JSON file (docs/metrics.md,
// "Calibrators"); no fitting (that needs the matcher, in eval).
#ifndef STEREODET_KITTI_SCORE_CALIBRATION_H_
#define STEREODET_KITTI_SCORE_CALIBRATION_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stereodet/kitti/object.h"

namespace stereodet {

enum class CalibrationMethod {
  kTemperature,  // p = sigmoid(x / T): one parameter, the ranking kept (Guo et al. 2017)
  kPlatt,        // p = sigmoid(a x + b): two parameters, the ranking kept (Platt 1999)
  kIsotonic,     // a non-decreasing step-wise linear map of the score (Zadrozny & Elkan 2002)
};
const char* CalibrationMethodName(CalibrationMethod method);  // "temperature", "platt", "isotonic"
std::optional<CalibrationMethod> ParseCalibrationMethod(std::string_view text);

// What temperature and Platt map: the score's logit x, the score itself when the scores are logits
// (ScoreCalibration::scores_are_logits), else log(s / (1 - s)) with s clamped to [1e-7, 1 - 1e-7]
// (a score of 0 or 1 would have an infinite one). The fits (eval/calibration_fit.h) take the same.
double CalibrationLogit(double score, bool scores_are_logits);

// One class's map: temperature and Platt of CalibrationLogit(score), isotonic of the raw score.
struct ScoreCalibrator {
  CalibrationMethod method = CalibrationMethod::kTemperature;
  // Temperature and Platt: p = 1 / (1 + exp(-(slope x + intercept))); temperature T = 1 / slope,
  // intercept 0.
  double slope = 1.0;
  double intercept = 0.0;
  // Isotonic: p at ascending raw scores `x` (non-decreasing `y`, in [0, 1]), linear between two of
  // them, y.front() below x.front() and y.back() above x.back() (scikit-learn's
  // IsotonicRegression(out_of_bounds="clip") prediction).
  std::vector<double> x, y;

  // The calibrated probability of `score`, in [0, 1]. Requires a finite score.
  double Apply(double score, bool scores_are_logits) const;
  // Throws std::invalid_argument on a non-finite or non-positive slope, a non-finite intercept,
  // or isotonic points that are empty, of two lengths, not ascending in x, decreasing in y or
  // outside [0, 1].
  void Check() const;
};

// The calibrators of a detector's classes, and what they were fitted on.
struct ScoreCalibration {
  // The scores the calibrators take are logits (fitted with --score-transform sigmoid).
  bool scores_are_logits = false;
  // By class, in the order fitted; names compare case-insensitively, as the evaluator's.
  std::vector<std::pair<std::string, ScoreCalibrator>> classes;
  // What the fit saw, written into the file for the record (split, frames, matcher, metric,
  // difficulty, overlap threshold, counts of TPs and FPs per class, ...): key / value pairs.
  std::vector<std::pair<std::string, std::string>> fitted_on;
  // Classes asked for that could not be fitted (`calibrate --skip-unfittable`: no true or no false
  // positive to fit on), each with why; they have no calibrator, so their scores stay as they are.
  std::vector<std::pair<std::string, std::string>> unfitted;

  // The class's calibrator, or null.
  const ScoreCalibrator* Find(std::string_view class_name) const;
  // Replaces the score of each detection of a calibrated class by its calibrated probability;
  // detections of other classes are left as they are. Returns how many were changed. Throws
  // std::invalid_argument on a detection of a calibrated class without a finite score.
  int64_t Apply(std::vector<Object>* detections) const;
  // Check() of every calibrator; throws std::invalid_argument on no class (fitted or unfitted) or
  // a class twice.
  void Check() const;
};

// The calibration file (JSON; docs/metrics.md, "Calibrators"): {"format": "stereodet score
// calibration", "version": 1, "scores_are_logits": false, "classes": [{"class": "Car", "method":
// "platt", "slope": .., "intercept": ..} | {.., "method": "isotonic", "x": [..], "y": [..]}],
// "fitted_on": {..}, "unfitted": [{"class": "Cyclist", "reason": ".."}] (only when some are)}.
std::string ScoreCalibrationToJson(const ScoreCalibration& calibration);
// Parses and checks a calibration file's text; errors (std::invalid_argument) name `source` and
// the field.
ScoreCalibration ParseScoreCalibration(std::string_view text, const std::string& source);
ScoreCalibration ReadScoreCalibration(const std::filesystem::path& path);
// Written atomically (a temporary file renamed).
void WriteScoreCalibration(const std::filesystem::path& path, const ScoreCalibration& calibration);

}  // namespace stereodet

#endif  // STEREODET_KITTI_SCORE_CALIBRATION_H_
