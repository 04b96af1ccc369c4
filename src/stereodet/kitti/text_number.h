// Internal to the kitti module: fast, strict number reading and round-trip number writing shared by
// the label and calib parsers. Not part of the public API.
#ifndef STEREODET_KITTI_TEXT_NUMBER_H_
#define STEREODET_KITTI_TEXT_NUMBER_H_

#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace stereodet::kitti_internal {

// Why a token is not an acceptable number; kOk when it is.
enum class NumberStatus { kOk, kNotANumber, kNotFinite, kOutOfRange };

// Reads the whole token as a finite double. Accepts one leading '+' (but not "+-1"), rejects text,
// trailing garbage, "nan", "inf" (kNotFinite) and values beyond double's range such as 1e999 or
// 1e-400 (kOutOfRange).
inline NumberStatus ReadFiniteDouble(std::string_view token, double* value) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token.front() == '-' || token.front() == '+')) {
      return NumberStatus::kNotANumber;
    }
  }
  if (token.empty()) return NumberStatus::kNotANumber;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  if (ec == std::errc::result_out_of_range && ptr == end) return NumberStatus::kOutOfRange;
  if (ec != std::errc() || ptr != end) return NumberStatus::kNotANumber;
  if (!std::isfinite(*value)) return NumberStatus::kNotFinite;
  return NumberStatus::kOk;
}

// Reads the whole token as an int (optional leading '+'); nullopt for anything else or overflow.
inline std::optional<int> ReadInt(std::string_view token) {
  if (!token.empty() && token.front() == '+') {
    token.remove_prefix(1);
    if (!token.empty() && (token.front() == '-' || token.front() == '+')) return std::nullopt;
  }
  if (token.empty()) return std::nullopt;
  int value = 0;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

// What is wrong with a token, for error messages ("is not a number", ...).
inline const char* NumberStatusMessage(NumberStatus status) {
  switch (status) {
    case NumberStatus::kOk:
      return "is a number";
    case NumberStatus::kNotANumber:
      return "is not a number";
    case NumberStatus::kNotFinite:
      return "is not a finite number";
    case NumberStatus::kOutOfRange:
      return "is out of the range of a double";
  }
  return "is not a number";
}

// Appends `value` as `format` with `precision` digits when that text reads back to exactly `value`,
// otherwise as the shortest text that does. Requires: `value` finite.
void AppendRoundTrip(std::string* out, double value, std::chars_format format, int precision);

// Appends the token quoted for an error message, shortened to 40 characters and with
// non-printable bytes escaped, so a binary file cannot flood or garble the terminal.
std::string QuoteToken(std::string_view token);

// The line of `text` that starts at *pos, without its '\n'; moves *pos past the '\n' (to
// text.size() + 1 after a last line without one). Callers loop `while (pos < text.size())`.
inline std::string_view NextLine(std::string_view text, size_t* pos) {
  const size_t start = *pos;
  const void* newline = std::memchr(text.data() + start, '\n', text.size() - start);
  const size_t end =
      newline ? static_cast<size_t>(static_cast<const char*>(newline) - text.data()) : text.size();
  *pos = end + 1;
  return text.substr(start, end - start);
}

}  // namespace stereodet::kitti_internal

#endif  // STEREODET_KITTI_TEXT_NUMBER_H_
