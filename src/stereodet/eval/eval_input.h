// Finding and reading the frames of an evaluation: the label folder, the detection folder, the
// split, and what was skipped on the way. The CLI (`stereodet eval`) and the Python module call
// this, then Evaluate().
//
//   EvalInputOptions in;
//   in.gt = "kitti";  in.det = "results/data";  in.split = "val";
//   EvalInput input = LoadEvalFrames(in);
//   for (const std::string& line : input.Notices()) std::cout << line << '\n';
//   EvalResult result = Evaluate(input.frames, options);
#ifndef STEREODET_EVAL_EVAL_INPUT_H_
#define STEREODET_EVAL_EVAL_INPUT_H_

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/frame_data.h"
#include "stereodet/util/shard.h"

namespace stereodet {

// The share of the labelled frames that may lack a detection file when no split is given (a
// detector that writes no file for a frame where it found nothing): above it, LoadEvalFrames
// refuses unless EvalInputOptions::missing_as_empty.
inline constexpr double kMaxMissingDetectionShare = 0.10;

struct EvalInputOptions {
  // Labels: a KITTI root (with training/label_2), a folder with label_2/ inside, or a folder of
  // label .txt files.
  std::filesystem::path gt;
  // Detections: a folder of detection .txt files, or one with data/ inside (the devkit's layout).
  std::filesystem::path det;
  // Frame ids, one per line: a file, or with a KITTI root a name under ROOT/ImageSets ("val").
  // Empty: every label file.
  std::string split;
  // Strict (default): the first bad line of a label or detection file throws a ParseError naming
  // file, line and field. Lenient: bad lines are skipped and listed in EvalInput::skipped_lines.
  bool lenient = false;
  // Without a split every label file is a frame to evaluate, and a frame without a detection file
  // is evaluated as one where the detector found nothing. A folder of detections for part of the
  // frames would then read as a weak detector (Car Moderate 83 as 39), so when more than
  // kMaxMissingDetectionShare of the labelled frames have no detection file LoadEvalFrames
  // refuses, unless this is set (`--missing-as-empty`). With a split, the split says which frames
  // count: a frame of it without a detection file is evaluated with no detections.
  bool missing_as_empty = false;
  // A detection line must have 16 fields, the score last. Set: a line of 15 (a label line) is read
  // as a detection of this score, so a folder of labels can stand in for detections in a sanity
  // check (`--score 1`: every label a detection of score 1, AP 1 on the labels themselves).
  std::optional<double> score_if_missing;
  int num_threads = 0;  // 0 = all hardware threads
  // Read only this shard of the frame list (util/shard.h: a contiguous range of the split's order,
  // or of the sorted label files). What is checked and reported about the folders (ignored files,
  // detection files without labels) is the whole list's, so every shard says the same.
  Shard shard;
  // Keep every read file's bytes in EvalInput::sources (for a shard's frames file).
  bool keep_sources = false;

  // Throws std::invalid_argument when gt or det is empty, num_threads < 0 or a bad shard.
  void Check() const;
};

// The bytes one frame's evaluation reads: what `eval --shard` keeps so that `eval merge` can
// evaluate the frames exactly as one process would (pipelines/evaluation.h).
struct EvalFrameSource {
  std::string id;
  std::string label_path;  // as LoadEvalFrames named it (in messages and lenient notices)
  std::string label_text;
  bool has_detections = false;  // false: no detection file (evaluated with no detections)
  std::string det_path;
  std::string det_text;
};

struct EvalInput {
  // One frame per id, in split order (without a split, ascending file name order).
  std::vector<EvalFrame> frames;
  std::filesystem::path label_dir, det_dir;  // the folders actually read
  // Ids of frames that have no detection file (evaluated with no detections).
  std::vector<std::string> frames_without_detections;
  // .txt files not evaluated, full paths in name order, detection folder first: detection files of
  // frames outside the split, and .txt files whose name is not a frame id (README.txt) in either
  // folder. Other files (README.md, hidden files) are ignored without a trace.
  std::vector<std::string> ignored_files;
  // Lenient mode: "FILE:LINE: field F: message" for each skipped line, frame order then line order.
  std::vector<std::string> skipped_lines;
  // What was read, as 16 hex digits: FNV-1a 64 (util/hash.h) over the frames' hashes in frame order
  // (8 bytes each, little-endian), a frame's hash being FNV-1a 64 over its id, a NUL, its label
  // file's bytes, a NUL and its detection file's bytes (none when the file is missing). Equal
  // inputs give equal hashes whatever the thread count.
  std::string input_hash;
  // The detection folder's run manifest (DET/run.json, written by `stereodet detect`), when it has
  // one (KITTI's own results have none): "TOOL VERSION: COMMAND LINE", else empty.
  std::string det_run;
  // With a manifest: the evaluated detection files (full paths, frame order) that it does not list
  // with their content hash, i.e. files another run wrote or changed. Empty without a manifest.
  std::vector<std::string> det_not_from_run;
  // With EvalInputOptions::keep_sources: the bytes of every frame, in frame order.
  std::vector<EvalFrameSource> sources;

  // One line each (no newline) for the user: frames without detections, ignored files (count and
  // the first), skipped lines (count), detection files not from the folder's run (count and the
  // first). Empty when there is nothing to say.
  std::vector<std::string> Notices() const;
};

// Finds the folders, reads the split and every frame's label and detection file (in parallel).
// Frame ids are digits only. Throws std::runtime_error (the message names the path) when a folder
// is missing, the split names a frame without a label file, no frame is left, or, without a
// split, a detection file has no label file; ParseError for a bad split line or, unless lenient,
// a bad label or detection line. A split name ("val") with a plain label folder is an error that
// says where it looked and how to pass the file.
EvalInput LoadEvalFrames(const EvalInputOptions& options);

// The frames, skipped lines, frames without detections and input hash of `sources`, parsed and
// hashed by the very code LoadEvalFrames uses (so the frames of N shards' sources, concatenated in
// shard order, are bit for bit those of one LoadEvalFrames of the whole list). Folder-level fields
// (label_dir, det_dir, ignored_files, det_run, det_not_from_run) are left empty; `sources` is
// moved into EvalInput::sources when keep_sources. Throws ParseError as LoadEvalFrames does.
EvalInput EvalInputFromSources(std::vector<EvalFrameSource> sources, bool lenient, int num_threads,
                               bool keep_sources = false,
                               std::optional<double> score_if_missing = std::nullopt);

}  // namespace stereodet

#endif  // STEREODET_EVAL_EVAL_INPUT_H_
