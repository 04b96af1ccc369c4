// Precision-recall curves exact at every score threshold, and their summaries (AP_R40, AP_R11,
// every-point AP, best F1).
#ifndef STEREODET_EVAL_CURVES_H_
#define STEREODET_EVAL_CURVES_H_

#include <cstdint>
#include <vector>

namespace stereodet {

// A change of the counts that happens when the score threshold drops to `score` (the thresholds
// t <= score include it).
struct CurveEvent {
  double score = 0.0;
  int32_t tp = 0, fp = 0, fn = 0;
  double similarity = 0.0;  // change of the orientation-similarity sum of the TPs
};

// Counts at one threshold: every detection with score >= threshold takes part.
struct CurvePoint {
  double threshold = 0.0;
  int64_t tp = 0, fp = 0, fn = 0;
  double precision = 0.0;  // tp / (tp + fp); 0 when there is no detection
  double recall = 0.0;     // tp / (tp + fn); 0 when there is no label
  // Sum over the TP pairs of (1 + cos(alpha_det - alpha_label)) / 2, and its ratio to tp + fp (the
  // devkit's AOS "precision"; 0 when there is no detection). Filled only where AOS is computed. In
  // the LET kinds, the sum of the TPs' longitudinal affinities and LET-APL's weighted precision.
  double similarity = 0.0;
  double orientation = 0.0;
};

// Sorts the events by descending score and sums them; FN starts at `num_valid_labels` (nothing
// detected). One point per distinct score, in descending threshold order. Events of equal score
// are summed in their order in `events` (a stable sort), so the similarity's floating-point sum is
// fixed by the events' order alone, not by a sort algorithm's choices.
std::vector<CurvePoint> BuildCurve(std::vector<CurveEvent> events, int64_t num_valid_labels);

// `point` with precision, recall and the orientation ratio filled from its counts.
CurvePoint FinishPoint(CurvePoint point);

// Interpolated AP in percent: the mean over recall levels r of max{precision(p) : recall(p) >= r}
// (0 if no point reaches r). R40: r = 1/40, ..., 40/40; R11: r = 0, 0.1, ..., 1. Points with no
// detection (tp + fp = 0) are skipped.
double InterpolatedApR40(const std::vector<CurvePoint>& curve);
double InterpolatedApR11(const std::vector<CurvePoint>& curve);
// PASCAL VOC 2010+ "every point" AP in percent: the area under the precision envelope, integrated
// over the recall changes.
double EveryPointAp(const std::vector<CurvePoint>& curve);
// Average orientation similarity in percent, interpolated like InterpolatedApR40/R11 with the
// orientation ratio in place of precision: the mean over r of max{orientation(p) : recall(p) >= r}.
// Perfect orientation makes it equal to the AP.
double InterpolatedAosR40(const std::vector<CurvePoint>& curve);
double InterpolatedAosR11(const std::vector<CurvePoint>& curve);

struct OperatingPoint {
  double threshold = 0.0;
  int64_t tp = 0, fp = 0, fn = 0;
  double precision = 0.0, recall = 0.0, f1 = 0.0;
};
OperatingPoint MakeOperatingPoint(double threshold, int64_t tp, int64_t fp, int64_t fn);
// The curve point of largest F1 (the highest threshold among ties); all zero for an empty curve.
OperatingPoint BestF1(const std::vector<CurvePoint>& curve);

}  // namespace stereodet

#endif  // STEREODET_EVAL_CURVES_H_
