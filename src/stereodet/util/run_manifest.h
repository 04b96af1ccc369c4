// The provenance record of an output folder (OUT/run.json) and the check that an output does not
// overlap an input. Every command that writes a folder users keep (detect, train; stereo records
// the same facts in its stereo.json, eval in results.json) writes one, so a folder tells which
// run made it: the tool and its version, the command line, the inputs, the settings and the frames
// written (each with a content or settings hash).
#ifndef STEREODET_UTIL_RUN_MANIFEST_H_
#define STEREODET_UTIL_RUN_MANIFEST_H_

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace stereodet {

// The manifest's file name in an output folder.
inline constexpr char kRunManifestFile[] = "run.json";

struct RunManifest {
  std::string tool;          // the command, e.g. "detect ssd"
  std::string version;       // StereodetVersion() when written by RunManifestToJson's caller
  std::string command_line;  // as the user typed it; empty when called from a library
  // Named inputs and their paths as given ("data" -> "/data/kitti", "model" -> "models/ssd-rgb").
  std::vector<std::pair<std::string, std::string>> inputs;
  // The settings that change the outputs' bytes: the text of one JSON object ("{}" when none).
  std::string settings_json = "{}";
  // The frames written, in order, each with a hash (16 hex digits: of the file written, or of the
  // settings that produced it).
  std::vector<std::pair<std::string, std::string>> frames;
};

// Pretty JSON (2 spaces, trailing newline): {"tool", "version", "command_line", "inputs": {name:
// path}, "settings": {...}, "frames": {id: hash}}. Throws std::invalid_argument if settings_json
// is not a JSON object.
std::string RunManifestToJson(const RunManifest& manifest);
// Parses what RunManifestToJson wrote; throws ParseError naming `source` and the field.
RunManifest RunManifestFromJson(const std::string& text, const std::string& source);

// Writes DIR/run.json atomically (the folder is created if missing). Throws std::runtime_error
// naming the file.
void WriteRunManifest(const std::filesystem::path& dir, const RunManifest& manifest);
// DIR/run.json, or nothing when the folder has none (an older folder, KITTI's own results).
// Throws ParseError for a file that is there but not a manifest.
std::optional<RunManifest> ReadRunManifest(const std::filesystem::path& dir);

// Throws std::invalid_argument when `out` and one of `inputs` overlap: the same folder, `out`
// inside an input, or an input inside `out` (canonical paths: links and `..` resolved, missing
// tails compared as written). The message names both paths, e.g. "--out /d/training/label_2 is
// inside the input --data /d/training; writing there would overwrite it; choose a folder outside
// it". Each input is (flag or role, path); empty paths are skipped.
void CheckOutputDoesNotOverlapInputs(
    const std::string& out_name, const std::filesystem::path& out,
    const std::vector<std::pair<std::string, std::filesystem::path>>& inputs);

// FNV-1a 64 of a file's bytes as 16 hex digits (util/hash.h). Throws std::runtime_error naming the
// file if it cannot be read.
std::string HashFileHex(const std::filesystem::path& path);

// Throws std::runtime_error naming `dir` in one line when it cannot be created or written (a
// read-only folder): creates it if missing, then writes and removes a hidden probe file. For
// commands whose writer (LibTorch) would otherwise fail late with a long trace.
void CheckFolderWritable(const std::filesystem::path& dir);

// Holds an exclusive lock on an output folder for as long as it lives, so that two runs writing
// into one folder (stereo, train: they write in place, resuming) cannot interleave. The lock is a
// hidden sibling file `.NAME.lock` (flock; released, and the file removed, by the destructor or
// when the process dies), so it never shows among the folder's outputs. Throws
// std::runtime_error naming the folder when another process holds it: "another run is writing
// into OUT (lock .OUT.lock held); wait for it or use another --out".
//
// `kind` names the lock file `.NAME.KIND` (default "lock"): a sharded run holds its shard's lock
// ("shard-K-of-N.lock") for its whole run and "manifest.lock" only while it merges its frames
// into DIR/run.json; with `wait` the constructor waits for the holder instead of throwing.
class OutputLock {
 public:
  explicit OutputLock(const std::filesystem::path& dir, const std::string& kind = "lock",
                      bool wait = false);
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;
  ~OutputLock();

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace stereodet

#endif  // STEREODET_UTIL_RUN_MANIFEST_H_
