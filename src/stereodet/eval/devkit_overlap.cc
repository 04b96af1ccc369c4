#include "stereodet/eval/devkit_overlap.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <vector>

// boost 1.74's rescale policy trips g++ 12's -Wmaybe-uninitialized once inlined (a false positive
// in boost's own code, not ours).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/geometry/algorithms/append.hpp>
#include <boost/geometry/algorithms/area.hpp>
#include <boost/geometry/algorithms/intersection.hpp>
#include <boost/geometry/algorithms/union.hpp>
#include <boost/geometry/geometries/point_xy.hpp>
#include <boost/geometry/geometries/polygon.hpp>
#pragma GCC diagnostic pop

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

namespace bg = boost::geometry;

// The devkit's Polygon typedef: boost's defaults, clockwise and closed.
using DevkitPoint = bg::model::d2::point_xy<double>;
using DevkitPolygon = bg::model::polygon<DevkitPoint>;

// The devkit's toPolygon. It builds the corners with a ublas matrix product, whose entries are
// accumulated from 0 in index order, then adds the location; written out here so that every
// rounding happens in the same order (0 + a keeps a, except that it turns -0 into +0). This file is
// compiled with -ffp-contract=off (CMakeLists.txt): the devkit's build has no fused multiply-add,
// so c * x + s * z must round twice here too; a contracted multiply-add (g++ contracts by default
// when the target has FMA, e.g. -march=native) rounds once and moves a corner by an ulp, which is
// exactly the difference this file exists to remove. The flag covers boost::geometry's own sums of
// products too (areas, side tests, intersection points), instantiated in this file only.
DevkitPolygon FootprintPolygon(const Box3D& box) {
  const double c = std::cos(box.rotation_y);
  const double s = std::sin(box.rotation_y);
  const double corner_x[4] = {box.l / 2, box.l / 2, -box.l / 2, -box.l / 2};
  const double corner_z[4] = {box.w / 2, -box.w / 2, -box.w / 2, box.w / 2};
  DevkitPolygon polygon;
  polygon.outer().reserve(5);
  for (int i = 0; i < 4; ++i) {
    double x = 0.0;
    x += c * corner_x[i];
    x += s * corner_z[i];
    x += box.location.x();
    double z = 0.0;
    z += -s * corner_x[i];
    z += c * corner_z[i];
    z += box.location.z();
    bg::append(polygon, DevkitPoint(x, z));
  }
  bg::append(polygon, polygon.outer().front());
  return polygon;
}

// Area of the first polygon of `polygons`, nullopt if there is none: the devkit looks only at the
// first one (two convex footprints meet in at most one polygon).
std::optional<double> FirstArea(const std::vector<DevkitPolygon>& polygons) {
  if (polygons.empty()) return std::nullopt;
  return bg::area(polygons.front());
}

std::optional<double> Overlap(OverlapKind kind, DevkitCriterion criterion, const Box3D& detection,
                              const Box3D& label) {
  const DevkitPolygon label_polygon = FootprintPolygon(label);
  const DevkitPolygon det_polygon = FootprintPolygon(detection);
  // Label first, as in the devkit: the operand order can change the last bits of the result.
  std::vector<DevkitPolygon> intersection;
  bg::intersection(label_polygon, det_polygon, intersection);
  const double inter_area = FirstArea(intersection).value_or(0.0);

  if (kind == OverlapKind::kBev) {
    // The devkit computes the union for both criteria and reads its first polygon unconditionally:
    // an empty union crashes it, whichever criterion was asked for.
    std::vector<DevkitPolygon> uni;
    bg::union_(label_polygon, det_polygon, uni);
    const std::optional<double> union_area = FirstArea(uni);
    if (!union_area) return std::nullopt;
    if (criterion == DevkitCriterion::kUnion) return inter_area / *union_area;
    return inter_area / bg::area(det_polygon);
  }

  // 3D: the devkit also computes a union here but never reads it, so nothing can crash.
  const double y_max = std::min(detection.location.y(), label.location.y());
  const double y_min = std::max(detection.location.y() - detection.h, label.location.y() - label.h);
  const double inter_volume = inter_area * std::max(0.0, y_max - y_min);
  const double det_volume = detection.h * detection.l * detection.w;
  if (criterion == DevkitCriterion::kDetectionSize) return inter_volume / det_volume;
  const double label_volume = label.h * label.l * label.w;
  return inter_volume / (det_volume + label_volume - inter_volume);
}

}  // namespace

std::optional<double> DevkitBoxOverlap(OverlapKind kind, DevkitCriterion criterion,
                                       const Box3D& detection, const Box3D& label) {
  STEREODET_CHECK(kind == OverlapKind::kBev || kind == OverlapKind::k3D)
      << "the devkit's polygon arithmetic is for BEV and 3D overlaps only";
  try {
    return Overlap(kind, criterion, detection, label);
  } catch (const std::exception&) {
    // boost::geometry's overlay may throw on input it finds invalid; uncaught in the devkit, that
    // ends it too: no answer, like an empty union.
    return std::nullopt;
  }
}

}  // namespace stereodet
