#include "stereodet/kitti/text_number.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

std::string ReadWholeFile(const std::filesystem::path& path) {
  // POSIX open/fstat/read rather than an ifstream: a KITTI split is thousands of small files and
  // the stream set-up would cost more than the parsing.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  STEREODET_CHECK_IO(fd >= 0) << "cannot read " << path.string() << ": " << std::strerror(errno);
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  STEREODET_CHECK_IO(::fstat(fd, &info) == 0)
      << "cannot read " << path.string() << ": " << std::strerror(errno);
  STEREODET_CHECK_IO(S_ISREG(info.st_mode)) << "cannot read " << path.string() << ": not a file";
  std::string contents;
  // One byte more than the size, so a single read() both fills the file and sees its end.
  contents.resize(static_cast<size_t>(info.st_size) + 1);
  size_t used = 0;
  while (true) {
    if (used == contents.size()) contents.resize(contents.size() * 2);
    const ssize_t got = ::read(fd, contents.data() + used, contents.size() - used);
    if (got < 0 && errno == EINTR) continue;
    STEREODET_CHECK_IO(got >= 0) << "cannot read " << path.string() << ": " << std::strerror(errno);
    if (got == 0) break;
    used += static_cast<size_t>(got);
  }
  contents.resize(used);
  return contents;
}

}  // namespace stereodet::kitti_internal
