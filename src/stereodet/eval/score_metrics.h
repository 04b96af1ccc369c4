// Metrics of an association at an operating point: Brier scores (three ways), the reliability curve
// and expected calibration error, and the 3D localization error of matched pairs by distance.
// Definitions: docs/metrics.md. Computed by score_metrics_internal.h's ScoreMetricsAccumulator.
#ifndef STEREODET_EVAL_SCORE_METRICS_H_
#define STEREODET_EVAL_SCORE_METRICS_H_

#include <cstdint>
#include <vector>

namespace stereodet {

// Means of Brier terms (NaN when there is no term, or when left out: WithoutProbabilities).
// s is a detection's score after EvalOptions::score_transform. Definitions: docs/metrics.md.
struct BrierScores {
  // Over labels (the default, the paper's recommendation): a fixed support, one term per valid
  // label of the cell whatever the detector did: (1 - s)^2 with s the score of its TP detection,
  // 1 otherwise (FN, or excused by an ignored detection). num_label_terms is the cell's
  // num_valid_labels for every detector.
  double over_labels = 0.0;
  int64_t num_label_terms = 0;
  // Over detections: one term per counted detection (TP or FP), (s - y)^2 with y = 1 for a TP.
  double over_detections = 0.0;
  int64_t num_detection_terms = 0;
  // Over all: the label terms above plus s^2 for each FP detection.
  double over_all = 0.0;
  int64_t num_all_terms = 0;
};

struct ReliabilityBin {
  double lower = 0.0, upper = 0.0;  // score range [lower, upper) ([lower, 1] for the last bin)
  int64_t count = 0;                // counted detections (TP or FP) in the bin
  double mean_score = 0.0;          // NaN if empty
  double tp_fraction = 0.0;         // NaN if empty
  // The mean of each detection's overlap with its label (a TP's matched overlap, 0 for a FP): what
  // LaECE compares the mean score with. NaN if empty or unknown (COCO mode).
  double mean_iou = 0.0;
};

struct CalibrationResult {
  std::vector<ReliabilityBin> bins;
  // Detection ECE: sum over bins of count / N * |mean_score - tp_fraction|; NaN if N = 0.
  double ece = 0.0;
  // Localization-aware ECE (LaECE, Oksuz et al. CVPR 2023), for the cell's class: sum over bins of
  // count / N * |mean_score - mean_iou|, a TP counting its matched overlap (IoU, BEV or 3D overlap
  // by the cell's kind) and a FP 0: a score should say how well the box fits, not only whether it
  // matched. NaN if N = 0 or an overlap is unknown (COCO mode). Like ece, over the detections at
  // the operating point only: misses do not count (docs/metrics.md, "Calibration").
  double laece = 0.0;
  // D-ECE (DeceOptions): sum over the joint bins of (score, box centre, box size) of count / N *
  // |mean score - TP fraction|, N the detections in some bin; NaN if N = 0 or the boxes are not
  // known (COCO mode). Over the detections at the operating point, as ece.
  double dece = 0.0;
  // Detections with a feature outside [0, 1] (a box reaching past the image, a score outside [0,
  // 1]), clamped into the end bins as netcal does.
  int64_t dece_outside = 0;
  int64_t num_detections = 0;
  int64_t num_out_of_range = 0;  // scores outside [0, 1], clamped into the end bins
};

struct DistanceBin {
  double lower_m = 0.0, upper_m = 0.0;  // label depth z in [lower, upper)
  int64_t count = 0;                    // TP pairs with 3D boxes on both sides
  double centre_error_mean_m = 0.0, centre_error_median_m = 0.0, centre_error_p90_m = 0.0;
  double depth_error_mean_m = 0.0;  // signed, detection z - label z
  double abs_depth_error_mean_m = 0.0, abs_depth_error_median_m = 0.0, abs_depth_error_p90_m = 0.0;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_SCORE_METRICS_H_
