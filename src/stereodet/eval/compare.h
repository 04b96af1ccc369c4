// Two detection sets on the same labels (for example stereo vs LiDAR): their 3D localization error
// per label-distance bin side by side, with the stereo depth-error model dz = z^2 / (b f) * dd.
#ifndef STEREODET_EVAL_COMPARE_H_
#define STEREODET_EVAL_COMPARE_H_

#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"

namespace stereodet {

struct CompareOptions {
  double baseline_m = 0.54;         // stereo baseline b (m); KITTI's is about 0.54
  double focal_px = 721.5377;       // focal length f (px)
  double disparity_error_px = 1.0;  // dd (px)
  void Check() const;               // throws std::invalid_argument unless all are finite and > 0
};

// One distance bin of one class x overlap kind x difficulty.
struct CompareRow {
  std::string class_name;
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  double lower_m = 0.0, upper_m = 0.0;  // label depth z in [lower, upper)
  int64_t count_a = 0, count_b = 0;     // TP pairs with 3D boxes on both sides
  double abs_depth_error_mean_a_m = 0.0, abs_depth_error_mean_b_m = 0.0;  // NaN for an empty bin
  double difference_b_minus_a_m = 0.0;  // mean |dz| of B minus that of A (NaN if either is)
  double centre_error_mean_a_m = 0.0, centre_error_mean_b_m = 0.0;
  double model_depth_error_m = 0.0;  // StereoDepthError at the bin centre
};

// The rows for every result evaluated in both `a` and `b` (same classes, kinds, difficulties and
// distance bins: both evaluated with the same EvalOptions), in `a`'s result order, bins ascending.
std::vector<CompareRow> CompareLocalization(const EvalResult& a, const EvalResult& b,
                                            const CompareOptions& options);

}  // namespace stereodet

#endif  // STEREODET_EVAL_COMPARE_H_
