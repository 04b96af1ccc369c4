#include "stereodet/eval/compare.h"

#include <cmath>
#include <stdexcept>

#include "stereodet/geometry/calibration.h"

namespace stereodet {

void CompareOptions::Check() const {
  for (const double v : {baseline_m, focal_px, disparity_error_px}) {
    if (!std::isfinite(v) || v <= 0) {
      throw std::invalid_argument(
          "compare needs finite, positive baseline, focal length and disparity error");
    }
  }
}

std::vector<CompareRow> CompareLocalization(const EvalResult& a, const EvalResult& b,
                                            const CompareOptions& options) {
  options.Check();
  std::vector<CompareRow> rows;
  for (const ClassResult& x : a.results) {
    const ClassResult* y = b.Find(x.class_name, x.metric, x.difficulty);
    if (!x.evaluated || y == nullptr || !y->evaluated) continue;
    for (size_t k = 0; k < x.localization.size() && k < y->localization.size(); ++k) {
      const DistanceBin& ba = x.localization[k];
      const DistanceBin& bb = y->localization[k];
      CompareRow row;
      row.class_name = x.class_name;
      row.metric = x.metric;
      row.difficulty = x.difficulty;
      row.lower_m = ba.lower_m;
      row.upper_m = ba.upper_m;
      row.count_a = ba.count;
      row.count_b = bb.count;
      row.abs_depth_error_mean_a_m = ba.abs_depth_error_mean_m;
      row.abs_depth_error_mean_b_m = bb.abs_depth_error_mean_m;
      row.difference_b_minus_a_m = bb.abs_depth_error_mean_m - ba.abs_depth_error_mean_m;
      row.centre_error_mean_a_m = ba.centre_error_mean_m;
      row.centre_error_mean_b_m = bb.centre_error_mean_m;
      row.model_depth_error_m = StereoDepthError((ba.lower_m + ba.upper_m) / 2, options.baseline_m,
                                                 options.focal_px, options.disparity_error_px);
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace stereodet
