#include "stereodet/eval/let.h"

#include <algorithm>
#include <cmath>

#include "stereodet/eval/frame_data.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

// Below this a range has no direction (Waymo's metric guards the same division with an epsilon).
constexpr double kMinRangeM = 1e-9;

}  // namespace

void LetOptions::Check() const {
  STEREODET_CHECK(std::isfinite(longitudinal_tolerance_fraction) &&
                  longitudinal_tolerance_fraction >= 0)
      << "LetOptions: longitudinal_tolerance_fraction must be finite and >= 0, got "
      << longitudinal_tolerance_fraction;
  STEREODET_CHECK(std::isfinite(min_longitudinal_tolerance_m) && min_longitudinal_tolerance_m >= 0)
      << "LetOptions: min_longitudinal_tolerance_m must be finite and >= 0, got "
      << min_longitudinal_tolerance_m;
  STEREODET_CHECK(longitudinal_tolerance_fraction > 0 || min_longitudinal_tolerance_m > 0)
      << "LetOptions: longitudinal_tolerance_fraction and min_longitudinal_tolerance_m are both 0 "
         "(no tolerance: no detection could match)";
  STEREODET_CHECK(sensor_m.allFinite()) << "LetOptions: sensor_m must be finite";
}

double LongitudinalAffinity(const Box3D& detection, const Box3D& label, const LetOptions& options) {
  const Eigen::Vector3d p = detection.Centre() - options.sensor_m;
  const Eigen::Vector3d g = label.Centre() - options.sensor_m;
  const double g_range = std::max(g.norm(), kMinRangeM);
  // The range error |P| cos(theta) - |G| = P . G / |G| - |G| = (P - G) . G / |G|: written as the
  // last, which is exactly 0 for P = G and keeps small errors' digits (Waymo computes the first,
  // dividing by |P| and multiplying by it again: the same value up to rounding).
  const double error = (p - g).dot(g) / g_range;
  const double tolerance = std::max(options.longitudinal_tolerance_fraction * g_range,
                                    options.min_longitudinal_tolerance_m);
  return std::clamp(1.0 - std::abs(error) / tolerance, 0.0, 1.0);
}

Box3D RangeAlignedBox(const Box3D& detection, const Box3D& label, const LetOptions& options) {
  const Eigen::Vector3d p = detection.Centre() - options.sensor_m;
  const Eigen::Vector3d g = label.Centre() - options.sensor_m;
  const double p_range_sq = std::max(p.squaredNorm(), kMinRangeM * kMinRangeM);
  // The closest point to G on the line through the sensor and P (t P minimises |t P - G|); t < 0
  // puts it behind the sensor, which Waymo's range alignment allows too.
  const double t = p.dot(g) / p_range_sq;
  Box3D aligned = detection;
  aligned.location = options.sensor_m + t * p + Eigen::Vector3d(0.0, detection.h / 2.0, 0.0);
  return aligned;
}

double LetOverlap(OverlapKind kind, const Box3D& detection, const Box3D& label,
                  const LetOptions& options) {
  return KittiBoxOverlap(PlainKind(kind), RangeAlignedBox(detection, label, options), label);
}

}  // namespace stereodet
