// Atomic file writing: write to a temporary file in the destination's folder, then rename over the
// destination. An interrupted run never leaves a half-written file that looks whole; at worst it
// leaves a hidden `.NAME.tmp-*` file, which readers ignore.
#ifndef STEREODET_UTIL_ATOMIC_FILE_H_
#define STEREODET_UTIL_ATOMIC_FILE_H_

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

// An output folder written as one run. Files go into a hidden staging folder beside `final_dir`
// (`.NAME.staging-PID-N`); Commit() puts it in place of `final_dir` with two renames (an existing
// `final_dir` is renamed aside, then removed). So the folder never mixes the files of two runs, two
// runs into one folder cannot interleave (the last to commit wins, whole), and an interrupted run
// leaves the previous folder as it was. Without Commit() the destructor removes the staging folder.
//
//   StagedFolder out(dir, "results.json");
//   WriteFileAtomically(out.path() / "results.json", ...);
//   out.Commit();
class StagedFolder {
 public:
  // Throws std::runtime_error, naming the folder, if `final_dir` exists and is not a folder, or is
  // a non-empty folder without the file `marker` (so it is not an earlier output of this kind and
  // replacing it could destroy someone's data).
  StagedFolder(std::filesystem::path final_dir, const std::string& marker);
  StagedFolder(const StagedFolder&) = delete;
  StagedFolder& operator=(const StagedFolder&) = delete;
  ~StagedFolder();

  // Where to write now: the staging folder (created empty).
  const std::filesystem::path& path() const { return staging_dir_; }
  const std::filesystem::path& final_path() const { return final_dir_; }

  // Replaces `final_dir` by the staging folder. Throws std::runtime_error naming the folder if a
  // rename fails (`final_dir` is then the previous run's or, if the second rename failed, absent
  // with the previous run kept as `.NAME.old-*` beside it, named in the message).
  void Commit();

 private:
  std::filesystem::path final_dir_;
  std::filesystem::path staging_dir_;
  bool committed_ = false;
};

// Reads a whole regular file (one read() for a file of the size fstat reports). Throws
// std::runtime_error naming the path if it cannot be read or is not a regular file (a FIFO, a
// folder), so a reader never blocks.
std::string ReadFile(const std::filesystem::path& path);

}  // namespace stereodet

#endif  // STEREODET_UTIL_ATOMIC_FILE_H_
