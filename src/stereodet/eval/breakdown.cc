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
  // (append, not "," + string: g++ 12 warns falsely on the latter, -Wrestrict)
  for (size_t i = 0; i < options.edges.size(); ++i) {
    if (i > 0) text.append(",");
    text.append(FormatEdge(options.edges[i]));
  }
  return text;
}

std::string BreakdownBinName(double lower, double upper) {
  std::string name = "[";
  name.append(FormatEdge(lower)).append(", ").append(FormatEdge(upper)).append(")");
  return name;
}

bool StableSelection::FilterKeeps(const Object& object, bool is_label) const {
  return PassesFilter(object, is_label, *conditions);
}

}  // namespace stereodet
