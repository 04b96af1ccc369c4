#include "stereodet/util/strings.h"

#include <fmt/format.h>

#include <bit>
#include <cctype>
#include <charconv>
#include <cstring>
#include <system_error>

namespace stereodet {

namespace {
template <typename T>
std::optional<T> ParseNumber(std::string_view text) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    // from_chars takes a '-' itself; a sign after the '+' ("+-1", "++1") is not a number.
    if (!text.empty() && (text.front() == '-' || text.front() == '+')) return std::nullopt;
  }
  if (text.empty()) return std::nullopt;
  T value{};
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  // out_of_range (1e999) is a number, just not a representable one: report it as not a number.
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

template <typename T>
std::string FormatShortestImpl(T value) {
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, ec == std::errc() ? ptr : buffer);
}
}  // namespace

std::optional<double> ParseDouble(std::string_view text) { return ParseNumber<double>(text); }
std::optional<float> ParseFloat(std::string_view text) { return ParseNumber<float>(text); }
std::optional<long long> ParseInt(std::string_view text) { return ParseNumber<long long>(text); }

std::vector<std::string_view> SplitWhitespace(std::string_view text) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && IsSpace(text[i])) ++i;
    const size_t start = i;
    while (i < text.size() && !IsSpace(text[i])) ++i;
    if (i > start) tokens.push_back(text.substr(start, i - start));
  }
  return tokens;
}

std::vector<std::string_view> Split(std::string_view text, char separator) {
  std::vector<std::string_view> tokens;
  size_t start = 0;
  while (true) {
    const size_t pos = text.find(separator, start);
    if (pos == std::string_view::npos) {
      tokens.push_back(text.substr(start));
      return tokens;
    }
    tokens.push_back(text.substr(start, pos - start));
    start = pos + 1;
  }
}

std::string_view Trim(std::string_view text) {
  while (!text.empty() && IsSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && IsSpace(text.back())) text.remove_suffix(1);
  return text;
}

std::string_view StripUtf8Bom(std::string_view text) {
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text;
}

std::string FormatShortest(double value) { return FormatShortestImpl(value); }
std::string FormatShortest(float value) { return FormatShortestImpl(value); }

char* WriteFmtShortest(char* it, double value) {
  // fmt 9's default double format (write(out, double) -> dragonbox::to_decimal -> do_write_float
  // with general format, no precision): the shortest digits, fixed notation when the exponent of
  // the first digit is in [-4, 16), else d[.ddd]e+XX with at least two exponent digits.
  constexpr uint64_t kExponentMask = 0x7ff0000000000000ULL;
  uint64_t bits = std::bit_cast<uint64_t>(value);
  if ((bits & kExponentMask) == kExponentMask) {  // nan, inf (fmt: "-nan" with the sign bit)
    if (bits >> 63) *it++ = '-';
    std::memcpy(it, (bits << 12) != 0 ? "nan" : "inf", 3);
    return it + 3;
  }
  if (bits >> 63) {
    *it++ = '-';
    value = -value;
  }
  const auto dec = fmt::detail::dragonbox::to_decimal(value);
  // The significand's digits, two at a time from the end (at most 17).
  static constexpr char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
      "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
      "8081828384858687888990919293949596979899";
  // The digits end at digits + 24, so that 24 bytes can be copied from any of them (the
  // fixed-size copies below compile to a few moves; what they write past the text is overwritten or
  // left beyond the end returned: the caller's kFmtShortestMaxChars).
  char digits[48];
  char* end = digits + 24;
  char* first = end;
  uint64_t sig64 = dec.significand;  // < 2^54: at most 17 digits
  // The low 8 digits of a long significand in 32-bit arithmetic (cheaper than 64-bit division),
  // then the rest, which fits 32 bits.
  if (sig64 >= 100000000) {
    const uint64_t high = sig64 / 100000000;
    uint32_t low = static_cast<uint32_t>(sig64 - high * 100000000);
    for (int k = 0; k < 4; ++k) {
      first -= 2;
      std::memcpy(first, kPairs + 2 * (low % 100), 2);
      low /= 100;
    }
    sig64 = high;
  }
  uint32_t sig = static_cast<uint32_t>(sig64);
  while (sig >= 100) {
    const uint32_t pair = sig % 100;
    sig /= 100;
    first -= 2;
    std::memcpy(first, kPairs + 2 * pair, 2);
  }
  if (sig >= 10) {
    first -= 2;
    std::memcpy(first, kPairs + 2 * sig, 2);
  } else {
    *--first = static_cast<char>('0' + sig);
  }
  const int n = static_cast<int>(end - first);
  const char* const d = first;
  const int exponent = dec.exponent;  // value = significand * 10^exponent
  const int first_exp = exponent + n - 1;
  if (first_exp < -4 || first_exp >= 16) {
    *it++ = d[0];
    if (n > 1) {
      *it++ = '.';
      std::memcpy(it, d + 1, 24);
      it += n - 1;
    }
    *it++ = 'e';
    int e = first_exp;
    *it++ = e < 0 ? '-' : '+';
    if (e < 0) e = -e;
    if (e >= 100) {
      if (e >= 1000) *it++ = static_cast<char>('0' + e / 1000);
      *it++ = static_cast<char>('0' + e / 100 % 10);
    }
    *it++ = static_cast<char>('0' + e / 10 % 10);
    *it++ = static_cast<char>('0' + e % 10);
  } else if (exponent >= 0) {  // 1234e2 -> 123400
    std::memcpy(it, d, 24);
    it += n;
    std::memset(it, '0', 16);  // exponent < 16 - n here
    it += exponent;
  } else if (n + exponent > 0) {  // 1234e-2 -> 12.34
    const int whole = n + exponent;
    std::memcpy(it, d, 24);
    it += whole;
    *it++ = '.';
    std::memcpy(it, d + whole, 24);
    it += n - whole;
  } else {  // 1234e-6 -> 0.001234
    *it++ = '0';
    *it++ = '.';
    std::memset(it, '0', 4);  // -(n + exponent) <= 4 here
    it += -(n + exponent);
    std::memcpy(it, d, 24);
    it += n;
  }
  return it;
}

void AppendFmtShortest(std::string& out, double value) {
  char text[kFmtShortestMaxChars];
  out.append(text, static_cast<size_t>(WriteFmtShortest(text, value) - text));
}

void AppendInt(std::string& out, int64_t value) {
  char text[24];
  const char* end = std::to_chars(text, text + sizeof(text), value).ptr;
  out.append(text, static_cast<size_t>(end - text));
}

bool EqualsIgnoreCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i]) continue;  // most comparisons are of equal names: no tolower call for them
    if (std::tolower(static_cast<unsigned char>(a[i])) !=
        std::tolower(static_cast<unsigned char>(b[i]))) {
      return false;
    }
  }
  return true;
}

}  // namespace stereodet
