#include "stereodet/kitti/file_checks.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

// An open file descriptor of a regular file, closed on scope exit. O_NONBLOCK so that a FIFO
// without a writer is refused instead of blocking the open.
class RegularFile {
 public:
  explicit RegularFile(const std::filesystem::path& path) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    STEREODET_CHECK_IO(fd_ >= 0) << "cannot open " << path.string() << ": " << std::strerror(errno);
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      STEREODET_THROW_IO() << path.string() << " is not a regular file";
    }
    size_ = static_cast<int64_t>(st.st_size);
  }
  ~RegularFile() { ::close(fd_); }
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;

  int64_t size() const { return size_; }

  // Reads exactly `count` bytes at `offset`; the caller checked that they lie inside the file.
  void ReadAt(int64_t offset, uint8_t* out, size_t count) const {
    size_t done = 0;
    while (done < count) {
      const ssize_t n = ::pread(fd_, out + done, count - done, static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      STEREODET_CHECK_IO(n > 0) << "cannot read " << path_.string() << ": "
                                << (n == 0 ? "unexpected end of file" : std::strerror(errno));
      done += static_cast<size_t>(n);
    }
  }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  int64_t size_ = 0;
};

uint32_t BigEndian32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

}  // namespace

void CheckPngFile(const std::filesystem::path& path) {
  const RegularFile file(path);
  // Signature (8), IHDR length (4) and type (4), width (4), height (4), 5 more bytes, CRC (4).
  constexpr int64_t kHeaderBytes = 33;
  // The IEND chunk: length 0, type, and the CRC of "IEND".
  constexpr std::array<uint8_t, 12> kIend = {0,   0,   0,    0,    'I',  'E',
                                             'N', 'D', 0xAE, 0x42, 0x60, 0x82};
  constexpr std::array<uint8_t, 8> kSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  STEREODET_CHECK_IO(file.size() >= kHeaderBytes + static_cast<int64_t>(kIend.size()))
      << path.string() << ": not a PNG image (" << file.size() << " bytes, too short)";
  std::array<uint8_t, kHeaderBytes> header{};
  file.ReadAt(0, header.data(), header.size());
  STEREODET_CHECK_IO(std::memcmp(header.data(), kSignature.data(), kSignature.size()) == 0)
      << path.string() << ": not a PNG image (no PNG signature)";
  STEREODET_CHECK_IO(BigEndian32(&header[8]) == 13 && std::memcmp(&header[12], "IHDR", 4) == 0)
      << path.string() << ": damaged PNG image (no IHDR chunk first)";
  const uint32_t width = BigEndian32(&header[16]), height = BigEndian32(&header[20]);
  STEREODET_CHECK_IO(width >= 1 && width <= 0x7FFFFFFFu && height >= 1 && height <= 0x7FFFFFFFu)
      << path.string() << ": damaged PNG image (header says " << width << " x " << height << " px)";
  std::array<uint8_t, kIend.size()> end{};
  file.ReadAt(file.size() - static_cast<int64_t>(end.size()), end.data(), end.size());
  STEREODET_CHECK_IO(end == kIend) << path.string() << ": truncated PNG image (" << file.size()
                                   << " bytes, no IEND chunk at the end)";
}

void CheckVelodyneFile(const std::filesystem::path& path) {
  const RegularFile file(path);
  STEREODET_CHECK_IO(file.size() % 16 == 0)
      << path.string() << ": a velodyne scan must be a multiple of 16 bytes (float32 x, y, z, "
      << "reflectance), got " << file.size() << " bytes";
}

}  // namespace stereodet
