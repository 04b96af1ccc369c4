// Small, strict text helpers for the file parsers.
#ifndef STEREODET_UTIL_STRINGS_H_
#define STEREODET_UTIL_STRINGS_H_

#include <cstdint>
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

// Appends exactly the text of fmt::format("{}", value) to `out`: the shortest decimal that reads
// back to `value`, in fixed notation for decimal exponents in [-4, 16) ("0.0001", "1", "0.5",
// "1e-05", "1e+16", "-0", "nan", "inf"). fmt's own call costs about twice as much, which matters
// to the writers of exact curves (millions of numbers; see docs/BENCHMARKS.md).
void AppendFmtShortest(std::string& out, double value);
// The same text written at `out`, which must have room for kFmtShortestMaxChars (the text is at
// most 25 characters; the bytes after it may be overwritten); returns its end.
inline constexpr int kFmtShortestMaxChars = 48;
char* WriteFmtShortest(char* out, double value);
// Appends the decimal text of `value` ("-12").
void AppendInt(std::string& out, int64_t value);

}  // namespace stereodet

#endif  // STEREODET_UTIL_STRINGS_H_
