#include "stereodet/eval/filter.h"

#include <cmath>

#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {
constexpr struct {
  FilterBound bound;
  const char* name;
} kBoundNames[] = {
    {FilterBound::kMinHeight, "min-height"},       {FilterBound::kMaxHeight, "max-height"},
    {FilterBound::kMinWidth, "min-width"},         {FilterBound::kMaxWidth, "max-width"},
    {FilterBound::kMinArea, "min-area"},           {FilterBound::kMaxArea, "max-area"},
    {FilterBound::kMinDistance, "min-distance"},   {FilterBound::kMaxDistance, "max-distance"},
    {FilterBound::kMaxOcclusion, "max-occlusion"}, {FilterBound::kMaxTruncation, "max-truncation"},
    {FilterBound::kDifficulty, "difficulty"},
};
}  // namespace

const char* FilterModeName(FilterMode mode) {
  return mode == FilterMode::kNaive ? "naive" : "stable";
}

std::optional<FilterMode> ParseFilterMode(std::string_view text) {
  if (text == "naive") return FilterMode::kNaive;
  if (text == "stable") return FilterMode::kStable;
  return std::nullopt;
}

const char* FilterBoundName(FilterBound bound) {
  for (const auto& entry : kBoundNames) {
    if (entry.bound == bound) return entry.name;
  }
  return "?";
}

std::optional<FilterBound> ParseFilterBound(std::string_view text) {
  for (const auto& entry : kBoundNames) {
    if (text == entry.name) return entry.bound;
  }
  return std::nullopt;
}

void FilterOptions::Check() const {
  for (const FilterCondition& c : conditions) {
    STEREODET_CHECK(!std::isnan(c.value)) << "filter " << FilterBoundName(c.bound) << " is NaN";
    if (c.bound == FilterBound::kDifficulty) {
      STEREODET_CHECK(c.value == 0 || c.value == 1 || c.value == 2)
          << "filter difficulty must be 0, 1 or 2, got " << c.value;
    }
  }
}

std::vector<FilterCondition> ParseFilterConditions(std::string_view text) {
  std::vector<FilterCondition> conditions;
  for (std::string_view part : Split(text, ',')) {
    part = Trim(part);
    if (part.empty()) continue;
    const size_t eq = part.find('=');
    STEREODET_CHECK(eq != std::string_view::npos)
        << "filter '" << part << "': expected NAME=VALUE, e.g. min-area=100";
    const std::string_view name = Trim(part.substr(0, eq));
    const std::string_view value_text = Trim(part.substr(eq + 1));
    const std::optional<FilterBound> bound = ParseFilterBound(name);
    STEREODET_CHECK(bound.has_value()) << "filter '" << part << "': unknown name '" << name
                                       << "' (min-/max-height, -width, -area, -distance, "
                                          "max-occlusion, max-truncation, difficulty)";
    FilterCondition condition;
    condition.bound = *bound;
    if (*bound == FilterBound::kDifficulty && !ParseDouble(value_text)) {
      const std::optional<Difficulty> difficulty = ParseDifficulty(value_text);
      STEREODET_CHECK(difficulty.has_value())
          << "filter '" << part << "': difficulty must be easy, moderate or hard";
      condition.value = static_cast<int>(*difficulty);
    } else {
      const std::optional<double> value = ParseDouble(value_text);
      STEREODET_CHECK(value.has_value() && std::isfinite(*value))
          << "filter '" << part << "': '" << value_text << "' is not a finite number";
      condition.value = *value;
    }
    conditions.push_back(condition);
  }
  FilterOptions{conditions, FilterMode::kStable}.Check();
  return conditions;
}

bool PassesFilter(const Object& object, bool is_label,
                  const std::vector<FilterCondition>& conditions) {
  for (const FilterCondition& c : conditions) {
    const double height = object.box.Height();
    const double width = object.box.Width();
    switch (c.bound) {
      case FilterBound::kMinHeight:
        if (!(height >= c.value)) return false;
        break;
      case FilterBound::kMaxHeight:
        if (!(height <= c.value)) return false;
        break;
      case FilterBound::kMinWidth:
        if (!(width >= c.value)) return false;
        break;
      case FilterBound::kMaxWidth:
        if (!(width <= c.value)) return false;
        break;
      case FilterBound::kMinArea:
        if (!(object.box.Area() >= c.value)) return false;
        break;
      case FilterBound::kMaxArea:
        if (!(object.box.Area() <= c.value)) return false;
        break;
      case FilterBound::kMinDistance:
        if (!(object.box3d.location.z() >= c.value)) return false;
        break;
      case FilterBound::kMaxDistance:
        if (!(object.box3d.location.z() <= c.value)) return false;
        break;
      case FilterBound::kMaxOcclusion:
        if (is_label && !(object.occluded <= c.value)) return false;
        break;
      case FilterBound::kMaxTruncation:
        if (is_label && !(object.truncated <= c.value)) return false;
        break;
      case FilterBound::kDifficulty:
        if (is_label &&
            !MeetsDifficulty(object, static_cast<Difficulty>(static_cast<int>(c.value)))) {
          return false;
        }
        break;
    }
  }
  return true;
}

}  // namespace stereodet
