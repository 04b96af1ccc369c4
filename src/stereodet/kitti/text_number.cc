#include "stereodet/kitti/text_number.h"

#include <cerrno>
#include <cstring>

#include "stereodet/util/check.h"

namespace stereodet::kitti_internal {

void AppendRoundTrip(std::string* out, double value, std::chars_format format, int precision) {
  char buffer[64];
  // Fixed notation of a huge number would need hundreds of digits and can never be "two decimals"
  // of a measured value; such numbers go straight to the shortest form.
  const bool try_format = format != std::chars_format::fixed || std::abs(value) < 1e15;
  if (try_format) {
    const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value, format, precision);
    if (ec == std::errc()) {
      double back = 0.0;
      const auto [back_ptr, back_ec] = std::from_chars(buffer, ptr, back);
      if (back_ec == std::errc() && back_ptr == ptr && back == value) {
        out->append(buffer, ptr);
        return;
      }
    }
  }
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, ec == std::errc() ? ptr : buffer);
}

std::string QuoteToken(std::string_view token) {
  constexpr size_t kMaxShown = 40;
  std::string quoted = "'";
  for (size_t i = 0; i < token.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      quoted.push_back(static_cast<char>(c));
    } else {
      static const char kHex[] = "0123456789abcdef";
      quoted.append("\\x").push_back(kHex[c >> 4]);
      quoted.push_back(kHex[c & 15]);
    }
  }
  if (token.size() > kMaxShown) quoted.append("...");
  quoted.push_back('\'');
  return quoted;
}

}  // namespace stereodet::kitti_internal
