#include "stereodet/util/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>

#include "stereodet/util/check.h"

namespace stereodet {
namespace fs = std::filesystem;

namespace {

// A name unique among the threads and processes writing into the same folder.
fs::path MakeTempPath(const fs::path& final_path) {
  static std::atomic<unsigned long> counter{0};
  const unsigned long n = counter.fetch_add(1);
  std::string name = ".";
  name.append(final_path.stem().string())
      .append(".tmp-")
      .append(std::to_string(::getpid()))
      .append("-")
      .append(std::to_string(n))
      .append(final_path.extension().string());
  return final_path.parent_path() / name;
}

void CreateParent(const fs::path& path) {
  const fs::path parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  STEREODET_CHECK_IO(!ec) << "cannot create folder " << parent.string() << ": " << ec.message();
}

}  // namespace

AtomicPath::AtomicPath(fs::path final_path)
    : final_path_(std::move(final_path)), temp_path_(MakeTempPath(final_path_)) {
  CreateParent(final_path_);
}

AtomicPath::~AtomicPath() {
  if (!committed_) {
    std::error_code ignored;
    fs::remove(temp_path_, ignored);
  }
}

void AtomicPath::Commit() {
  STEREODET_CHECK_IO(!committed_) << "AtomicPath::Commit called twice for " << final_path_.string();
  std::error_code ec;
  STEREODET_CHECK_IO(fs::exists(temp_path_, ec))
      << "cannot write " << final_path_.string() << ": the temporary file was not written";
  fs::rename(temp_path_, final_path_, ec);
  STEREODET_CHECK_IO(!ec) << "cannot write " << final_path_.string() << ": " << ec.message();
  committed_ = true;
}

void WriteFileAtomically(const fs::path& path, std::string_view contents) {
  AtomicPath out(path);
  {
    std::FILE* file = std::fopen(out.temp_path().c_str(), "wb");
    STEREODET_CHECK_IO(file != nullptr)
        << "cannot write " << path.string() << ": " << std::strerror(errno);
    const size_t written =
        contents.empty() ? 0 : std::fwrite(contents.data(), 1, contents.size(), file);
    const bool ok = written == contents.size() && std::fflush(file) == 0;
    const int close_status = std::fclose(file);
    STEREODET_CHECK_IO(ok && close_status == 0)
        << "cannot write " << path.string() << ": " << std::strerror(errno);
  }
  out.Commit();
}

namespace {

// "3000 bytes", "12.5 MB", "5.0 GB" (decimal units).
std::string HumanBytes(uint64_t bytes) {
  char text[32];
  if (bytes < 1000000) {
    std::snprintf(text, sizeof(text), "%llu bytes", static_cast<unsigned long long>(bytes));
  } else if (bytes < 1000000000) {
    std::snprintf(text, sizeof(text), "%.1f MB", static_cast<double>(bytes) / 1e6);
  } else {
    std::snprintf(text, sizeof(text), "%.1f GB", static_cast<double>(bytes) / 1e9);
  }
  return text;
}

// Reads up to `max_bytes` of a regular file; with `whole`, a longer file is an error. POSIX
// open/fstat/read (RegularFileReader) rather than an ifstream: a KITTI split is thousands of small
// files and the stream set-up (and its seeks) would cost more than the parsing. The read loop also
// grows past st_size, so /proc files (size 0) read whole. A file of the size fstat reports takes
// one read().
std::string ReadRegularFile(const fs::path& path, uint64_t max_bytes, bool whole,
                            const char* what) {
  RegularFileReader reader(path, what);
  const std::string& name = reader.name();
  const uint64_t size = reader.size();
  STEREODET_CHECK_IO(!whole || size <= max_bytes)
      << "cannot read " << name << ": it is " << HumanBytes(size) << ", more than the "
      << HumanBytes(max_bytes) << " read of one file";
  const uint64_t wanted = std::min(size, max_bytes);
  std::string contents;
  // One byte more than the size, so a single read() both fills the file and sees its end.
  contents.resize(static_cast<size_t>(wanted) + (whole ? 1 : 0));
  size_t used = 0;
  while (true) {
    if (used == contents.size()) {
      if (!whole) break;
      STEREODET_CHECK_IO(used <= max_bytes) << "cannot read " << name << ": it grew past the "
                                            << HumanBytes(max_bytes) << " read of one file";
      contents.resize(std::min<uint64_t>(contents.size() * 2, max_bytes + 1));
    }
    const size_t got = reader.Read(contents.data() + used, contents.size() - used);
    if (got == 0) break;
    used += got;
    // Exactly the size fstat reported: that is the whole file (one more byte was asked for, so a
    // file that grew since would have filled the buffer). No second read() just to see the end:
    // reading thousands of small files, that was a fifth of the system calls.
    if (whole && size > 0 && used == size) break;
  }
  STEREODET_CHECK_IO(!whole || used <= max_bytes) << "cannot read " << name << ": it grew past the "
                                                  << HumanBytes(max_bytes) << " read of one file";
  contents.resize(used);
  return contents;
}

}  // namespace

// fstat before reading, so a FIFO or a folder is refused instead of blocking (O_NONBLOCK: opening
// a FIFO without a writer would block; it does nothing to a regular file).
RegularFileReader::RegularFileReader(const fs::path& path, const char* what)
    : name_(what == nullptr ? path.string() : std::string(what) + " " + path.string()) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  STEREODET_CHECK_IO(fd_ >= 0) << "cannot read " << name_ << ": " << std::strerror(errno);
  struct stat info {};
  const bool stat_ok = ::fstat(fd_, &info) == 0;
  const int stat_errno = errno;
  if (!stat_ok || !S_ISREG(info.st_mode)) {
    ::close(fd_);
    STEREODET_CHECK_IO(stat_ok) << "cannot read " << name_ << ": " << std::strerror(stat_errno);
    STEREODET_CHECK_IO(false) << "cannot read " << name_ << ": not a regular file";
  }
  size_ = static_cast<uint64_t>(info.st_size);
}

RegularFileReader::~RegularFileReader() { ::close(fd_); }

size_t RegularFileReader::Read(char* into, size_t bytes) {
  while (true) {
    const ssize_t got = ::read(fd_, into, bytes);
    if (got < 0 && errno == EINTR) continue;
    STEREODET_CHECK_IO(got >= 0) << "cannot read " << name_ << ": " << std::strerror(errno);
    return static_cast<size_t>(got);
  }
}

std::string ReadFile(const fs::path& path, uint64_t max_bytes, const char* what) {
  return ReadRegularFile(path, max_bytes, /*whole=*/true, what);
}

std::string ReadFileHead(const fs::path& path, size_t bytes) {
  return ReadRegularFile(path, bytes, /*whole=*/false, nullptr);
}

}  // namespace stereodet
