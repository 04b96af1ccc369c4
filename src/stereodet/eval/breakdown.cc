#include "stereodet/eval/breakdown.h"

#include <cmath>
#include <sstream>

#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

constexpr struct {
  BreakdownAxis axis;
  const char* name;
} kAxisNames[] = {
    {BreakdownAxis::kDistance, "distance"},   {BreakdownAxis::kHeight, "height"},
    {BreakdownAxis::kOcclusion, "occlusion"}, {BreakdownAxis::kTruncation, "truncation"},
    {BreakdownAxis::kColumn, "column"},
};

std::optional<double> ParseEdge(std::string_view text) {
  if (text == "inf" || text == "+inf") return std::numeric_limits<double>::infinity();
  if (text == "-inf") return -std::numeric_limits<double>::infinity();
  const std::optional<double> value = ParseDouble(text);
  if (!value || !std::isfinite(*value)) return std::nullopt;
  return value;
}

std::string FormatEdge(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream out;
  out << v;
  return out.str();
}

bool InBin(std::optional<double> value, double lower, double upper) {
  return value && *value >= lower && *value < upper;
}

}  // namespace

const char* BreakdownAxisName(BreakdownAxis axis) {
  for (const auto& entry : kAxisNames) {
    if (entry.axis == axis) return entry.name;
  }
  return "?";
}

std::optional<BreakdownAxis> ParseBreakdownAxis(std::string_view text) {
  for (const auto& entry : kAxisNames) {
    if (text == entry.name) return entry.axis;
  }
  return std::nullopt;
}

std::optional<double> BreakdownValue(BreakdownAxis axis, const Object& object, bool is_label) {
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

void BreakdownOptions::Check() const {
  STEREODET_CHECK(edges.size() >= 2) << "breakdown " << BreakdownAxisName(axis)
                                     << " needs at least 2 edges (one bin), got " << edges.size();
  for (size_t i = 0; i < edges.size(); ++i) {
    STEREODET_CHECK(!std::isnan(edges[i]))
        << "breakdown " << BreakdownAxisName(axis) << ": edge " << i + 1 << " is NaN";
    STEREODET_CHECK(std::isfinite(edges[i]) || (i == 0 && edges[i] < 0) ||
                    (i + 1 == edges.size() && edges[i] > 0))
        << "breakdown " << BreakdownAxisName(axis)
        << ": only the first edge may be -inf and only the last inf";
    if (i > 0) {
      STEREODET_CHECK(edges[i] > edges[i - 1])
          << "breakdown " << BreakdownAxisName(axis) << ": edges must increase, got "
          << FormatEdge(edges[i - 1]) << " then " << FormatEdge(edges[i]);
    }
  }
}

BreakdownOptions ParseBreakdown(std::string_view text) {
  const size_t eq = text.find('=');
  STEREODET_CHECK(eq != std::string_view::npos)
      << "breakdown '" << text << "': expected AXIS=EDGES, e.g. distance=0,30,50,inf";
  const std::string_view name = Trim(text.substr(0, eq));
  const std::optional<BreakdownAxis> axis = ParseBreakdownAxis(name);
  STEREODET_CHECK(axis.has_value()) << "breakdown '" << text << "': unknown axis '" << name
                                    << "' (distance, height, occlusion, truncation, column)";
  BreakdownOptions options;
  options.axis = *axis;
  options.edges.clear();
  for (std::string_view part : Split(text.substr(eq + 1), ',')) {
    part = Trim(part);
    const std::optional<double> edge = ParseEdge(part);
    STEREODET_CHECK(edge.has_value())
        << "breakdown '" << text << "': '" << part << "' is not a number (or inf, -inf)";
    options.edges.push_back(*edge);
  }
  options.Check();
  return options;
}

std::string BreakdownText(const BreakdownOptions& options) {
  std::string text = std::string(BreakdownAxisName(options.axis)) + "=";
  for (size_t i = 0; i < options.edges.size(); ++i) {
    text += (i > 0 ? "," : "") + FormatEdge(options.edges[i]);
  }
  return text;
}

std::string BreakdownBinName(double lower, double upper) {
  return "[" + FormatEdge(lower) + ", " + FormatEdge(upper) + ")";
}

bool StableSelection::KeepsLabel(const Object& label) const {
  if (conditions != nullptr) return PassesFilter(label, true, *conditions);
  return InBin(BreakdownValue(axis, label, true), lower, upper);
}

bool StableSelection::KeepsDetection(const Object& detection) const {
  if (conditions != nullptr) return PassesFilter(detection, false, *conditions);
  const std::optional<double> value = BreakdownValue(axis, detection, false);
  return !value || InBin(value, lower, upper);  // no value: counted in every bin
}

bool StableSelection::KeepsPair(const Object& label, const Object& detection) const {
  if (conditions != nullptr) {
    return PassesFilter(label, true, *conditions) && PassesFilter(detection, false, *conditions);
  }
  return KeepsLabel(label);
}

}  // namespace stereodet
