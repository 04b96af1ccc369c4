#include "stereodet/util/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

// A hidden sibling of `dir` named `.NAME.KIND-PID-N`, unique among threads and processes.
fs::path SiblingName(const fs::path& dir, const char* kind) {
  static std::atomic<unsigned long> counter{0};
  const unsigned long n = counter.fetch_add(1);
  std::string name = ".";
  name.append(dir.filename().string()).append(".").append(kind).append("-");
  name.append(std::to_string(::getpid())).append("-").append(std::to_string(n));
  return dir.parent_path() / name;
}

// `dir` without a trailing separator, so that filename() names the folder itself.
fs::path WithoutTrailingSeparator(fs::path dir) {
  dir = dir.lexically_normal();
  if (!dir.has_filename() && dir.has_parent_path()) dir = dir.parent_path();
  return dir;
}

}  // namespace

StagedFolder::StagedFolder(fs::path final_dir, const std::string& marker)
    : final_dir_(WithoutTrailingSeparator(std::move(final_dir))) {
  std::error_code ec;
  if (fs::exists(final_dir_, ec)) {
    STEREODET_CHECK_IO(fs::is_directory(final_dir_, ec))
        << final_dir_.string() << " exists and is not a folder";
    const bool empty = fs::is_empty(final_dir_, ec);
    STEREODET_CHECK_IO(empty || fs::exists(final_dir_ / marker, ec))
        << final_dir_.string() << " is a folder with other files in it (it holds no " << marker
        << ", so it is not an earlier output of this command); give a new or empty folder";
  }
  staging_dir_ = SiblingName(final_dir_, "staging");
  fs::create_directories(staging_dir_, ec);
  STEREODET_CHECK_IO(!ec) << "cannot create folder " << staging_dir_.string() << ": "
                          << ec.message();
}

StagedFolder::~StagedFolder() {
  if (!committed_) {
    std::error_code ignored;
    fs::remove_all(staging_dir_, ignored);
  }
}

void StagedFolder::Commit() {
  STEREODET_CHECK_IO(!committed_) << "StagedFolder::Commit called twice for "
                                  << final_dir_.string();
  std::error_code ec;
  fs::path old;
  if (fs::exists(final_dir_, ec)) {
    old = SiblingName(final_dir_, "old");
    fs::rename(final_dir_, old, ec);
    STEREODET_CHECK_IO(!ec) << "cannot replace " << final_dir_.string() << ": " << ec.message();
  }
  fs::rename(staging_dir_, final_dir_, ec);
  STEREODET_CHECK_IO(!ec) << "cannot write " << final_dir_.string() << ": " << ec.message()
                          << (old.empty() ? "" : "; the previous run is kept as " + old.string());
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);  // best effort: the new run is in place
}

std::string ReadFile(const fs::path& path) {
  // POSIX open/fstat/read rather than an ifstream: a KITTI split is thousands of small files and
  // the stream set-up (and its seeks) would cost more than the parsing. fstat before reading, so a
  // FIFO or a folder is refused instead of blocking (O_NONBLOCK: opening a FIFO without a writer
  // would block; it does nothing to a regular file); the read loop also grows past st_size, so
  // /proc files (size 0) read whole. A file of the size fstat reports takes one read().
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  STEREODET_CHECK_IO(fd >= 0) << "cannot read " << path.string() << ": " << std::strerror(errno);
  struct FdCloser {
    int fd;
    ~FdCloser() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  STEREODET_CHECK_IO(::fstat(fd, &info) == 0)
      << "cannot read " << path.string() << ": " << std::strerror(errno);
  STEREODET_CHECK_IO(S_ISREG(info.st_mode))
      << "cannot read " << path.string() << ": not a regular file";
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
    // Exactly the size fstat reported: that is the whole file (one more byte was asked for, so a
    // file that grew since would have filled the buffer). No second read() just to see the end:
    // reading thousands of small files, that was a fifth of the system calls.
    if (info.st_size > 0 && used == static_cast<size_t>(info.st_size)) break;
  }
  contents.resize(used);
  return contents;
}

}  // namespace stereodet
