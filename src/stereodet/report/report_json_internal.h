// Reading results.json in the report, and writing its CSVs: the number, text and fixed-point
// helpers the report module's files share (the report module's own; not for users).
#ifndef STEREODET_REPORT_REPORT_JSON_INTERNAL_H_
#define STEREODET_REPORT_REPORT_JSON_INTERNAL_H_

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace stereodet::report_internal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A number, or NaN for anything else (null: not computed).
inline double Num(const nlohmann::json& j) { return j.is_number() ? j.get<double>() : kNaN; }
// j[key] as a number; NaN where j is not an object holding it.
inline double Num(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) ? Num(j[key]) : kNaN;
}

// j[key] as numbers (NaN for the entries that are not); empty where j[key] is not an array.
inline std::vector<double> Numbers(const nlohmann::json& j, const char* key) {
  std::vector<double> out;
  if (!j.is_object() || !j.contains(key) || !j[key].is_array()) return out;
  for (const nlohmann::json& v : j[key]) out.push_back(Num(v));
  return out;
}

// j[key] as text; "" where j is not an object holding a string there.
inline std::string Str(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : "";
}

// A CSV field: the shortest text that reads back as `v`, or empty for NaN (not computed).
inline std::string Csv(double v) { return std::isnan(v) ? std::string() : fmt::format("{}", v); }

// "0.459" (`decimals` places), or "-" for NaN and infinities.
inline std::string Fixed(double v, int decimals) {
  return std::isfinite(v) ? fmt::format("{:.{}f}", v, decimals) : std::string("-");
}

}  // namespace stereodet::report_internal

#endif  // STEREODET_REPORT_REPORT_JSON_INTERNAL_H_
