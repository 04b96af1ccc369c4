// Atomic file writing: write to a temporary file in the destination's folder, then rename over the
// destination. An interrupted run never leaves a half-written file that looks whole; at worst it leaves
// a hidden `.NAME.tmp-*` file, which readers ignore.
#ifndef STEREODET_UTIL_ATOMIC_FILE_H_
#define STEREODET_UTIL_ATOMIC_FILE_H_

#include <filesystem>
#include <string>
#include <string_view>

namespace stereodet {

// Writes `contents` to `path` atomically, creating missing parent folders.
// Throws std::runtime_error naming the path on any I/O failure; the destination is then untouched.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents);

// For writers that need a path rather than bytes (cv::imwrite picks the encoder from the extension, so
// the temporary keeps it):
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

  // Renames the temporary over the final path. Throws std::runtime_error if the temporary is missing
  // or the rename fails.
  void Commit();

 private:
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  bool committed_ = false;
};

// Reads a whole file. Throws std::runtime_error naming the path if it cannot be read.
std::string ReadFile(const std::filesystem::path& path);

}  // namespace stereodet

#endif  // STEREODET_UTIL_ATOMIC_FILE_H_
