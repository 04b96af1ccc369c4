// Filters on labels and detections (box size, distance, occlusion, truncation, difficulty) and the
// two ways of applying them:
//   naive  - strike the labels and detections that fail, then match (common practice);
//   stable - match the unfiltered sets, then keep the pairs whose label and detection both pass;
//            unmatched labels and detections count only if they pass (the paper's "stable" filter).
#ifndef STEREODET_EVAL_FILTER_H_
#define STEREODET_EVAL_FILTER_H_

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/kitti/object.h"

namespace stereodet {

enum class FilterMode { kNaive, kStable };
const char* FilterModeName(FilterMode mode);  // "naive", "stable"
std::optional<FilterMode> ParseFilterMode(std::string_view text);

// A bound on one property of an object. Box sizes are from the 2D box (px), distance is the depth
// z of the 3D location (m). Occlusion, truncation and difficulty bind labels only (detection files
// carry no meaningful values there): detections always pass them.
enum class FilterBound {
  kMinHeight,
  kMaxHeight,
  kMinWidth,
  kMaxWidth,
  kMinArea,
  kMaxArea,  // px, px^2
  kMinDistance,
  kMaxDistance,  // m
  kMaxOcclusion,
  kMaxTruncation,  // labels only
  kDifficulty,     // labels only: value 0, 1, 2 = the label must meet Easy, Moderate, Hard
};
// "min-height", "max-height", "min-width", "max-width", "min-area", "max-area", "min-distance",
// "max-distance", "max-occlusion", "max-truncation", "difficulty".
const char* FilterBoundName(FilterBound bound);
std::optional<FilterBound> ParseFilterBound(std::string_view text);

struct FilterCondition {
  FilterBound bound = FilterBound::kMinArea;
  double value = 0.0;
};

struct FilterOptions {
  std::vector<FilterCondition> conditions;  // all must hold; empty = no filter
  FilterMode mode = FilterMode::kStable;

  bool empty() const { return conditions.empty(); }
  void Check() const;  // throws std::invalid_argument on a NaN value or a bad difficulty
};

// Parses "min-area=100,max-distance=40" (names as above; difficulty=easy|moderate|hard in any case,
// as ParseDifficulty, or 0|1|2).
// Throws std::invalid_argument naming the bad part.
std::vector<FilterCondition> ParseFilterConditions(std::string_view text);

// Whether `object` passes every condition. `is_label` selects the label-only bounds.
bool PassesFilter(const Object& object, bool is_label,
                  const std::vector<FilterCondition>& conditions);

}  // namespace stereodet

#endif  // STEREODET_EVAL_FILTER_H_
