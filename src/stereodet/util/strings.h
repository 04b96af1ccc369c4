// Small, strict text helpers for the file parsers.
#ifndef STEREODET_UTIL_STRINGS_H_
#define STEREODET_UTIL_STRINGS_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stereodet {

// The whole of `text` as a number, or nullopt if anything but a number is there ("1.5x", "", " 1").
// Accepts "nan" and "inf" (callers decide whether non-finite values are allowed) and a leading '+'.
std::optional<double> ParseDouble(std::string_view text);
std::optional<float> ParseFloat(std::string_view text);
std::optional<long long> ParseInt(std::string_view text);

// Splits on runs of spaces, tabs, '\r' and '\n'; no empty tokens.
std::vector<std::string_view> SplitWhitespace(std::string_view text);
// Splits on `separator`, keeping empty tokens ("a,,b" -> {"a", "", "b"}).
std::vector<std::string_view> Split(std::string_view text, char separator);

std::string_view Trim(std::string_view text);

// `text` without a leading UTF-8 byte-order mark (EF BB BF), which Windows editors put at the start
// of a text file; the text parsers (labels, detections, calibrations, splits) read a file through
// this, so the mark never becomes part of its first token.
std::string_view StripUtf8Bom(std::string_view text);

// Case-insensitive ASCII comparison (strcasecmp): "car" equals "Car"; bytes >= 0x80 compare
// exactly.
bool EqualsIgnoreCase(std::string_view a, std::string_view b);

// Shortest decimal text that reads back to exactly `value` (std::to_chars round-trip form), e.g.
// 1.5 -> "1.5", 0.1f -> "0.1". Used by writers that must round-trip exactly.
std::string FormatShortest(double value);
std::string FormatShortest(float value);

}  // namespace stereodet

#endif  // STEREODET_UTIL_STRINGS_H_
