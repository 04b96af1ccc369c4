// Breakdowns: every figure of a class x overlap kind x difficulty cell again for the bins of one
// property (distance, 2D box height, occlusion, truncation, image column), from one matching of the
// whole set (`eval --breakdown distance=0,30,50,inf`).
//
// A bin counts what the unfiltered association gives, as the paper's stable filter does, with one
// difference that makes the bins of an axis a partition of the matched pairs: a true-positive pair
// counts in the bin of its label (the ground truth decides, as in Waymo's range breakdown), a label
// alone (FN) in its own bin, a detection alone (FP) in its own bin, and a detection that has no
// value on the axis (a 2D detection's distance, any detection's occlusion or truncation) in every
// bin of the axis: such a false positive cannot be placed, so each bin carries it (conservative).
// Hence no bin holds more TPs, FNs or FPs than the whole cell, the bins' TPs and FNs add up to the
// cell's (labels outside every bin aside), and so do their FPs when every detection has a value.
#ifndef STEREODET_EVAL_BREAKDOWN_H_
#define STEREODET_EVAL_BREAKDOWN_H_

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/filter.h"
#include "stereodet/kitti/object.h"

namespace stereodet {

enum class BreakdownAxis {
  kDistance,    // depth z of the 3D box's location, m (camera frame); none for a 2D detection
  kHeight,      // 2D box height, px
  kOcclusion,   // KITTI's occluded (0 visible .. 3 unknown); labels only
  kTruncation,  // KITTI's truncated (0 .. 1); labels only
  kColumn,      // 2D box centre's column u, px (image bands: left, centre, right)
};
// "distance", "height", "occlusion", "truncation", "column".
const char* BreakdownAxisName(BreakdownAxis axis);
std::optional<BreakdownAxis> ParseBreakdownAxis(std::string_view text);

// `object`'s value on `axis`; nullopt where it has none (a detection without a 3D box on the
// distance axis, a detection on the occlusion and truncation axes). Inline: a breakdown reads it
// for every label and detection of every frame, cell and bin.
inline std::optional<double> BreakdownValue(BreakdownAxis axis, const Object& object,
                                            bool is_label) {
  switch (axis) {
    case BreakdownAxis::kDistance:
      // A label always has its location (KITTI's DontCare regions are no valid label anywhere); a
      // 2D detector's file says -1000.
      if (!is_label && !object.Has3D()) return std::nullopt;
      return object.box3d.location.z();
    case BreakdownAxis::kHeight:
      return object.box.Height();
    case BreakdownAxis::kOcclusion:
      if (!is_label) return std::nullopt;
      return static_cast<double>(object.occluded);
    case BreakdownAxis::kTruncation:
      if (!is_label) return std::nullopt;
      return object.truncated;
    case BreakdownAxis::kColumn:
      return 0.5 * (object.box.left + object.box.right);
  }
  return std::nullopt;
}

// One axis and its bin edges: bins [edges[i], edges[i + 1]) for i < edges.size() - 1.
struct BreakdownOptions {
  BreakdownAxis axis = BreakdownAxis::kDistance;
  std::vector<double> edges = {0, 30, 50, std::numeric_limits<double>::infinity()};  // Waymo's, m
  int num_bins() const { return static_cast<int>(edges.size()) - 1; }
  // Throws std::invalid_argument: fewer than 2 edges, a NaN, edges not strictly increasing, or an
  // infinite edge other than -inf first or +inf last.
  void Check() const;
};

// Parses "distance=0,30,50,inf" (axis as above; edges as numbers, "inf" and "-inf" allowed at the
// ends). Throws std::invalid_argument naming the bad part.
BreakdownOptions ParseBreakdown(std::string_view text);

// "distance=0,30,50,inf": the text ParseBreakdown reads back.
std::string BreakdownText(const BreakdownOptions& options);

// "[0, 30)", "[50, inf)": how reports name a bin.
std::string BreakdownBinName(double lower, double upper);

// What a stable count keeps of the unfiltered association: either the stable filter's conditions
// (filter.h: a pair when its label and its detection both pass) or one breakdown bin (this
// header's rule). Exactly one of the two is set.
struct StableSelection {
  const std::vector<FilterCondition>* conditions = nullptr;
  // The bin [lower, upper) of `axis`, when `conditions` is null.
  BreakdownAxis axis = BreakdownAxis::kDistance;
  double lower = 0.0, upper = 0.0;

  static StableSelection Filter(const std::vector<FilterCondition>& conditions) {
    StableSelection s;
    s.conditions = &conditions;
    return s;
  }
  static StableSelection Bin(BreakdownAxis axis, double lower, double upper) {
    StableSelection s;
    s.axis = axis;
    s.lower = lower;
    s.upper = upper;
    return s;
  }

  // A label alone (FN, or valid label count).
  bool KeepsLabel(const Object& label) const {
    if (conditions != nullptr) return FilterKeeps(label, true);
    const std::optional<double> value = BreakdownValue(axis, label, true);
    return value && *value >= lower && *value < upper;
  }
  // A detection alone (FP); one without a value on the axis is counted in every bin.
  bool KeepsDetection(const Object& detection) const {
    if (conditions != nullptr) return FilterKeeps(detection, false);
    const std::optional<double> value = BreakdownValue(axis, detection, false);
    return !value || (*value >= lower && *value < upper);
  }
  // A TP pair: both objects for a filter, the label alone for a bin.
  bool KeepsPair(const Object& label, const Object& detection) const {
    if (conditions != nullptr) return FilterKeeps(label, true) && FilterKeeps(detection, false);
    return KeepsLabel(label);
  }

 private:
  bool FilterKeeps(const Object& object, bool is_label) const;  // PassesFilter(.., *conditions)
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_BREAKDOWN_H_
