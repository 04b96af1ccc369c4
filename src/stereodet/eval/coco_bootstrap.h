// Bootstrap intervals over images for COCO mode's 12 summary numbers (eval/coco.h), and paired
// intervals of the difference between two detection sets of the same ground truth.
//
//   BootstrapOptions bootstrap;                  // 1000 resamples, seed 1, 95 %
//   const CocoBootstrapResult b = BootstrapCoco(gt, dets, CocoEvalOptions(), bootstrap);
//   b.stats[0].lower, b.stats[0].upper           // AP@[.50:.95]'s interval
//
// A resample draws N of the N images with replacement (BootstrapFrameCounts over the images in
// image-id order): image i is taken w_i times. Its 12 numbers are exactly EvaluateCoco's on the
// data set in which every image is repeated w_i times, the copies next to each other in image
// order (CocoBootstrapTest.EqualsEvaluateCocoOnMaterialisedResamples), computed without matching
// anything again: matching is per image, so every detection keeps what the matcher made of it,
// and only the accumulation (the recall counts, the precision envelope at the 101 recall points)
// and the summary are redone per resample. Either matcher (CocoEvalOptions::matcher). With
// score_metrics the Brier numbers of the summary are resampled too (score_stats below).
#ifndef STEREODET_EVAL_COCO_BOOTSTRAP_H_
#define STEREODET_EVAL_COCO_BOOTSTRAP_H_

#include <array>
#include <cstdint>
#include <vector>

#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/coco.h"

namespace stereodet {

struct CocoBootstrapResult {
  int num_resamples = 0;
  uint64_t seed = 0;
  double confidence = 0.0;
  CocoMatcher matcher = CocoMatcher::kCoco;
  BootstrapMethod method = BootstrapMethod::kPercentile;  // how the bounds were read
  int64_t num_images = 0;
  // By CocoEvalResult::stats' order. estimate: EvaluateCoco's number (-1 where it has none, as
  // there); a resample where a number is -1 (no ground truth in its slice) leaves it out (NaN in
  // samples).
  std::array<BootstrapInterval, kNumCocoStats> stats;
  // With CocoEvalOptions::score_metrics: the operating-point numbers' intervals, in score_stats'
  // order (BL, BL50, BL75, BD, ..., BA75); the ECE ones are not resampled (NaN), as calibration is
  // not in KITTI mode. A resample's Brier numbers are its cells' sums weighted by the images'
  // counts: EvaluateCoco's on the materialised image list up to rounding (1e-12), not bit for bit.
  std::array<BootstrapInterval, kNumCocoScoreStats> score_stats;
  double seconds = 0.0;  // wall time, the evaluation included
};

// Intervals of EvaluateCoco(gt, dets, options)'s 12 numbers. `result`, when given, receives that
// evaluation. Requires what EvaluateCoco requires, and bootstrap.Check().
CocoBootstrapResult BootstrapCoco(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                                  const CocoEvalOptions& options, const BootstrapOptions& bootstrap,
                                  CocoEvalResult* result = nullptr);

// Two detection sets of the same ground truth, resampled with the same image counts: a and b are
// BootstrapCoco's results for each; difference holds, per number, the estimate A - B and the
// percentile interval of the resamples' A - B (over the resamples where both are defined; NaN
// estimate where either has none). `result_a` and `result_b`, when given, receive the two
// evaluations (EvaluateCoco's of each set).
struct CocoPairedBootstrapResult {
  CocoBootstrapResult a, b, difference;
};
CocoPairedBootstrapResult PairedBootstrapCoco(const CocoGroundTruth& gt,
                                              const std::vector<CocoDetection>& dets_a,
                                              const std::vector<CocoDetection>& dets_b,
                                              const CocoEvalOptions& options,
                                              const BootstrapOptions& bootstrap,
                                              CocoEvalResult* result_a = nullptr,
                                              CocoEvalResult* result_b = nullptr);

}  // namespace stereodet

#endif  // STEREODET_EVAL_COCO_BOOTSTRAP_H_
