// Atomic file writing: write to a temporary file in the destination's folder, then rename over the
// destination. An interrupted run never leaves a half-written file that looks whole; at worst it
// leaves a hidden `.NAME.tmp-*` file, which readers ignore.
#ifndef STEREODET_UTIL_ATOMIC_FILE_H_
#define STEREODET_UTIL_ATOMIC_FILE_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace stereodet {

// Writes `contents` to `path` atomically, creating missing parent folders.
// Throws std::runtime_error naming the path on any I/O failure; the destination is then untouched.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents);

// For writers that need a path rather than bytes (cv::imwrite picks the encoder from the extension,
// so the temporary keeps it):
//
//   AtomicPath out(final_path);
//   cv::imwrite(out.temp_path().string(), image);
//   out.Commit();   // rename; without it the destructor removes the temporary
class AtomicPath {
 public:
  explicit AtomicPath(std::filesystem::path final_path);
  AtomicPath(const AtomicPath&) = delete;
  AtomicPath& operator=(const AtomicPath&) = delete;
  ~AtomicPath();

  const std::filesystem::path& temp_path() const { return temp_path_; }
  const std::filesystem::path& final_path() const { return final_path_; }

  // Renames the temporary over the final path. Throws std::runtime_error if the temporary is
  // missing or the rename fails.
  void Commit();

 private:
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  bool committed_ = false;
};

// The largest file ReadFile reads by default: 4 GiB. Far above any input the project reads whole
// (a KITTI image is about 1 MB, a scan 2 MB, a model 10 MB, a results.json of 3769 frames 100 MB),
// and below what would exhaust a machine's memory, so a huge or sparse file gets a message
// instead of std::bad_alloc.
inline constexpr uint64_t kMaxReadFileBytes = uint64_t{4} << 30;

// Reads a whole regular file (one read() for a file of the size fstat reports). The one checked
// path every input file of the project is read through, images included. Throws
// std::runtime_error naming the path if it cannot be read, is not a regular file (a FIFO, a
// folder, a device: opened without blocking, so a reader never hangs) or is larger than
// `max_bytes` ("... is 5.0 GB, more than the 4.0 GB read of one file"). `what`, when given, names
// the kind of file in the messages: "cannot read image PATH: not a regular file".
std::string ReadFile(const std::filesystem::path& path, uint64_t max_bytes = kMaxReadFileBytes,
                     const char* what = nullptr);

// The first `bytes` bytes of a regular file (fewer if it is shorter), with ReadFile's checks.
std::string ReadFileHead(const std::filesystem::path& path, size_t bytes);

// A regular file read front to back in pieces the caller sizes, for a reader that parses as it
// reads instead of holding the whole file (ReadFile's checks and messages; `what` as there):
//
//   RegularFileReader reader(path, "COCO results");
//   while (const size_t got = reader.Read(block.data(), block.size())) Parse(block, got);
class RegularFileReader {
 public:
  // Opens the file. Throws std::runtime_error naming it if it cannot be opened or is not a
  // regular file.
  explicit RegularFileReader(const std::filesystem::path& path, const char* what = nullptr);
  RegularFileReader(const RegularFileReader&) = delete;
  RegularFileReader& operator=(const RegularFileReader&) = delete;
  ~RegularFileReader();

  // The size fstat reported when the file was opened, in bytes.
  uint64_t size() const { return size_; }
  // The file named as in the messages ("COCO results PATH").
  const std::string& name() const { return name_; }

  // Reads up to `bytes` (> 0) bytes into `into`; returns how many, 0 only at the end of the file.
  // Throws std::runtime_error naming the file on a read error.
  size_t Read(char* into, size_t bytes);

 private:
  std::string name_;
  int fd_ = -1;
  uint64_t size_ = 0;
};

}  // namespace stereodet

#endif  // STEREODET_UTIL_ATOMIC_FILE_H_
