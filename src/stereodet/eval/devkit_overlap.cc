#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <exception>
#include <optional>
#include <unordered_map>
#include <vector>

#include "stereodet/eval/devkit_overlap_internal.h"

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

// The intersection and union areas boost gives for one pair of footprints (label first), each
// computed when first asked for. `kThrew`: boost threw (the devkit would end there).
struct Overlay {
  enum State : uint8_t { kUnknown, kValue, kNoPolygon, kThrew };
  State intersection = kUnknown, union_ = kUnknown;
  double intersection_area = 0.0, union_area = 0.0;
};

// Memory of the last pairs' overlays, per thread. An evaluation asks for the same pair in BEV and
// in 3D (both use the same intersection), and a low detection of any class is matched against
// the labels of every class; boost takes ~10 us per operation, a look-up well under 0.1 us. The
// key is the exact bits of the ten numbers the footprints are made of, so a hit returns what
// boost would compute again.
class OverlayMemory {
 public:
  Overlay& Find(const Box3D& detection, const Box3D& label) {
    if (memory_.size() >= kMaxPairs) memory_.clear();
    return memory_[Key{{Bits(label.l), Bits(label.w), Bits(label.rotation_y),
                        Bits(label.location.x()), Bits(label.location.z()), Bits(detection.l),
                        Bits(detection.w), Bits(detection.rotation_y), Bits(detection.location.x()),
                        Bits(detection.location.z())}}];
  }

 private:
  static constexpr size_t kMaxPairs = 1 << 16;
  struct Key {
    std::array<uint64_t, 10> bits;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      uint64_t h = 0x9e3779b97f4a7c15ull;
      for (const uint64_t b : k.bits) h = (h ^ b) * 0x100000001b3ull + (h >> 29);
      return static_cast<size_t>(h);
    }
  };
  static uint64_t Bits(double v) { return std::bit_cast<uint64_t>(v); }
  std::unordered_map<Key, Overlay, KeyHash> memory_;
};

// Area of the first polygon of boost's `op` on the two footprints, into *state / *area.
template <typename Op>
void Compute(Op op, Overlay::State* state, double* area) {
  try {
    std::vector<DevkitPolygon> polygons;
    op(&polygons);
    const std::optional<double> first = FirstArea(polygons);
    *state = first ? Overlay::kValue : Overlay::kNoPolygon;
    *area = first.value_or(0.0);
  } catch (const std::exception&) {
    // boost::geometry's overlay may throw on input it finds invalid; uncaught in the devkit, that
    // ends it too: no answer, like an empty union.
    *state = Overlay::kThrew;
  }
}

std::optional<double> Overlap(OverlapKind kind, DevkitCriterion criterion, const Box3D& detection,
                              const Box3D& label) {
  thread_local OverlayMemory memory;
  Overlay& overlay = memory.Find(detection, label);
  std::optional<DevkitPolygon> label_polygon, det_polygon;
  auto polygons = [&] {
    if (!label_polygon) {
      label_polygon = FootprintPolygon(label);
      det_polygon = FootprintPolygon(detection);
    }
  };
  if (overlay.intersection == Overlay::kUnknown) {
    polygons();
    // Label first, as in the devkit: the operand order can change the last bits of the result.
    Compute(
        [&](std::vector<DevkitPolygon>* out) {
          bg::intersection(*label_polygon, *det_polygon, *out);
        },
        &overlay.intersection, &overlay.intersection_area);
  }
  if (overlay.intersection == Overlay::kThrew) return std::nullopt;
  const double inter_area = overlay.intersection_area;  // 0 if there is no polygon

  if (kind == OverlapKind::kBev) {
    // The devkit computes the union for both criteria and reads its first polygon unconditionally:
    // an empty union crashes it, whichever criterion was asked for.
    if (overlay.union_ == Overlay::kUnknown) {
      polygons();
      Compute(
          [&](std::vector<DevkitPolygon>* out) { bg::union_(*label_polygon, *det_polygon, *out); },
          &overlay.union_, &overlay.union_area);
    }
    if (overlay.union_ != Overlay::kValue) return std::nullopt;
    if (criterion == DevkitCriterion::kUnion) return inter_area / overlay.union_area;
    polygons();
    return inter_area / bg::area(*det_polygon);
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
  return Overlap(kind, criterion, detection, label);
}

}  // namespace stereodet
