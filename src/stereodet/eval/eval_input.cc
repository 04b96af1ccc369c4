#include "stereodet/eval/eval_input.h"

#include <dirent.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

namespace fs = std::filesystem;

bool IsFrameId(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

fs::path LabelDir(const fs::path& p) {
  if (fs::is_directory(p / "training" / "label_2")) return p / "training" / "label_2";
  if (fs::is_directory(p / "label_2")) return p / "label_2";
  STEREODET_CHECK_IO(fs::is_directory(p)) << "--gt: " << p.string() << " is not a folder";
  return p;
}

// A frame's file name that is not a regular file (a folder, a FIFO, a link to nothing or to
// itself) would count as "no file" for its frame, silently: it is an error naming it.
void ThrowNotARegularFrameFile(const std::string& path) {
  STEREODET_THROW_IO() << path << " is not a regular file (a folder, a FIFO, or a link to "
                       << "nothing); a frame's file must be one";
}

// Whether `name` (a folder entry) is a .txt file name that is not hidden, and its stem.
bool TxtStem(std::string_view name, std::string_view* stem) {
  constexpr std::string_view kTxt = ".txt";
  if (name.empty() || name[0] == '.' || name.size() <= kTxt.size() ||
      name.substr(name.size() - kTxt.size()) != kTxt) {
    return false;
  }
  *stem = name.substr(0, name.size() - kTxt.size());
  return true;
}

// Whether `dir` holds a frame file (NNNNNN.txt) at its top, whatever its kind.
bool HoldsFrameFiles(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    std::string_view stem;
    if (TxtStem(name, &stem) && IsFrameId(stem)) return true;
  }
  return false;
}

fs::path DetectionDir(const fs::path& p) {
  if (fs::is_directory(p / "data")) {
    // The devkit's layout (DIR/data/ID.txt) and a flat one in the same folder: which is meant
    // cannot be told, and reading one silently would evaluate the wrong detections.
    STEREODET_CHECK_IO(!HoldsFrameFiles(p))
        << "--det: " << p.string() << " holds detection files both at its top and in data/ "
        << "(the devkit's layout); give the folder that holds the ones to evaluate";
    return p / "data";
  }
  STEREODET_CHECK_IO(fs::is_directory(p)) << "--det: " << p.string() << " is not a folder";
  return p;
}

// FrameStems through std::filesystem: for the folders readdir() cannot read, so that the error is
// the one std::filesystem gives.
std::set<std::string> FrameStemsFs(const fs::path& dir, std::vector<std::string>* not_ids) {
  std::set<std::string> stems;
  std::set<std::string> others;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string& full = e.path().native();
    const std::string_view name = std::string_view(full).substr(full.rfind('/') + 1);
    std::string_view stem;
    if (!TxtStem(name, &stem)) continue;
    std::error_code ec;
    if (!e.is_regular_file(ec)) {
      if (IsFrameId(stem)) ThrowNotARegularFrameFile(full);
      continue;
    }
    if (IsFrameId(stem)) {
      stems.emplace(stem);
    } else {
      others.insert(full);
    }
  }
  not_ids->insert(not_ids->end(), others.begin(), others.end());
  return stems;
}

// The stems of the .txt files of `dir` that are frame ids; other .txt files go to `not_ids`
// (full paths, dir / name, in name order). Hidden files and files of other extensions are skipped;
// a symbolic link counts as what it points to. Listed with readdir(): a folder of thousands of
// frames made std::filesystem's path objects (one per entry, split into components) cost 3,700
// instructions an entry, a sixth of reading and parsing the files themselves.
std::set<std::string> FrameStems(const fs::path& dir, std::vector<std::string>* not_ids) {
  DIR* const handle = ::opendir(dir.c_str());
  if (handle == nullptr) return FrameStemsFs(dir, not_ids);
  struct Closer {
    DIR* handle;
    ~Closer() { ::closedir(handle); }
  } closer{handle};
  // dir / name, as directory_iterator names its entries.
  const std::string prefix = (dir / "").native();
  std::vector<std::string> stems, others;
  std::string full;
  while (true) {
    errno = 0;
    const dirent* entry = ::readdir(handle);
    if (entry == nullptr) {
      if (errno != 0) return FrameStemsFs(dir, not_ids);  // its error
      break;
    }
    std::string_view stem;
    if (!TxtStem(entry->d_name, &stem)) continue;
    full.assign(prefix).append(entry->d_name);
    bool regular = entry->d_type == DT_REG;
    if (entry->d_type == DT_UNKNOWN || entry->d_type == DT_LNK) {
      struct stat info {};
      regular = ::stat(full.c_str(), &info) == 0 && S_ISREG(info.st_mode);
    }
    if (!regular) {
      if (IsFrameId(stem)) ThrowNotARegularFrameFile(full);
      continue;
    }
    if (IsFrameId(stem)) {
      stems.emplace_back(stem);
    } else {
      others.push_back(full);
    }
  }
  std::sort(stems.begin(), stems.end());
  std::sort(others.begin(), others.end());
  not_ids->insert(not_ids->end(), others.begin(), others.end());
  return std::set<std::string>(stems.begin(), stems.end());
}

// A split file of a plain label folder (no KITTI root to look a name up in).
std::vector<std::string> ReadSplitFile(const fs::path& gt, const std::string& split) {
  std::error_code ec;
  if (!fs::is_regular_file(split, ec)) {
    // A name such as "val": say where it was looked for, and where it probably is.
    std::string found;
    fs::path dir = fs::absolute(gt, ec).lexically_normal();
    for (int up = 0; up < 3 && !dir.empty(); ++up, dir = dir.parent_path()) {
      fs::path candidate = dir / "ImageSets" / split;
      if (!candidate.has_extension()) candidate += ".txt";
      if (fs::is_regular_file(candidate, ec)) {
        found = candidate.string();
        break;
      }
      if (dir == dir.parent_path()) break;
    }
    const std::string image_sets =
        "ImageSets/" + split + (fs::path(split).has_extension() ? "" : ".txt");
    STEREODET_THROW_IO() << "--split " << split << ": no such file. --gt " << gt.string()
                         << " is a folder of label files, not a KITTI root (a folder with "
                            "training/label_2 and ImageSets/), so a split name is not looked up; "
                            "looked for the file '"
                         << split << "' and for " << image_sets
                         << " in --gt and the two folders above it"
                         << (found.empty() ? ": none there" : ": found " + found)
                         << ". Pass the split file itself: --split "
                         << (found.empty() ? "ROOT/" + image_sets : found)
                         << ", or the KITTI root: --gt ROOT";
  }
  return ParseSplit(ReadFile(split), split);
}

std::vector<std::string> ReadIds(const fs::path& gt, const std::string& split) {
  if (fs::is_directory(gt / "training")) return KittiDataset(gt).ReadSplit(split);
  return ReadSplitFile(gt, split);
}

// Fills det_run and det_not_from_run from DET/run.json, when there is one.
// One frame parsed from its bytes, and its hash (EvalInput::input_hash).
struct ParsedFrame {
  EvalFrame frame;
  bool has_detections = false;
  std::vector<std::string> problems;
  uint64_t hash = 0;
};

// The one place a frame's bytes become an EvalFrame (LoadEvalFrames and EvalInputFromSources).
ParsedFrame ParseSource(const EvalFrameSource& source, bool lenient,
                        std::optional<double> score_if_missing) {
  const std::string_view nul("\0", 1);
  ParsedFrame out;
  out.frame.id = source.id;
  out.has_detections = source.has_detections;
  ObjectFile labels =
      ParseObjects(source.label_text, source.label_path, {ObjectFileKind::kLabel, lenient});
  out.frame.labels = std::move(labels.objects);
  out.problems = std::move(labels.problems);
  out.hash = Fnv1a64(nul, Fnv1a64(source.label_text, Fnv1a64(nul, Fnv1a64(source.id))));
  if (source.has_detections) {
    // With a score for lines that lack one, a line may have 15 fields or 16 (kAny, each line on
    // its own); the 15-field ones get that score.
    const ObjectFileKind kind =
        score_if_missing ? ObjectFileKind::kAny : ObjectFileKind::kDetection;
    ObjectFile dets = ParseObjects(source.det_text, source.det_path, {kind, lenient});
    if (score_if_missing) {
      for (Object& object : dets.objects) {
        if (!object.score) object.score = *score_if_missing;
      }
    }
    out.frame.detections = std::move(dets.objects);
    out.problems.insert(out.problems.end(), dets.problems.begin(), dets.problems.end());
    out.hash = Fnv1a64(source.det_text, out.hash);
  }
  return out;
}

// The frames, frames without detections, skipped lines (frame order, then line order) and the
// input hash of `parsed`, into `in`.
void FinishFrames(std::vector<ParsedFrame> parsed, EvalInput* in) {
  uint64_t input_hash = kFnv1a64Offset;
  in->frames.reserve(parsed.size());
  for (ParsedFrame& p : parsed) {
    if (!p.has_detections) in->frames_without_detections.push_back(p.frame.id);
    in->skipped_lines.insert(in->skipped_lines.end(), p.problems.begin(), p.problems.end());
    char bytes[8];
    for (int b = 0; b < 8; ++b) bytes[b] = static_cast<char>(p.hash >> (8 * b) & 0xff);
    input_hash = Fnv1a64(std::string_view(bytes, 8), input_hash);
    in->frames.push_back(std::move(p.frame));
  }
  in->input_hash = HashHex(input_hash);
}

void CheckDetectionRun(EvalInput& in) {
  const std::optional<RunManifest> manifest = ReadRunManifest(in.det_dir);
  if (!manifest) return;
  in.det_run = manifest->tool + " " + manifest->version + ": " + manifest->command_line;
  std::map<std::string, std::string> listed(manifest->frames.begin(), manifest->frames.end());
  std::set<std::string> without(in.frames_without_detections.begin(),
                                in.frames_without_detections.end());
  for (const EvalFrame& frame : in.frames) {
    if (without.count(frame.id)) continue;
    const fs::path path = in.det_dir / (frame.id + ".txt");
    const auto it = listed.find(frame.id);
    if (it == listed.end() || it->second != HashFileHex(path)) {
      in.det_not_from_run.push_back(path.string());
    }
  }
}

}  // namespace

void EvalInputOptions::Check() const {
  STEREODET_CHECK(!gt.empty()) << "--gt is required";
  STEREODET_CHECK(!det.empty()) << "--det is required";
  STEREODET_CHECK(num_threads >= 0) << "num_threads = " << num_threads << ", must be >= 0";
  STEREODET_CHECK(!score_if_missing || std::isfinite(*score_if_missing))
      << "--score must be a finite number, got " << *score_if_missing;
  shard.Check();
}

std::vector<std::string> EvalInput::Notices() const {
  std::vector<std::string> out;
  if (!frames_without_detections.empty()) {
    out.push_back("frames without a detection file (no detections): " +
                  std::to_string(frames_without_detections.size()));
  }
  if (!ignored_files.empty()) {
    out.push_back("ignored " + std::to_string(ignored_files.size()) +
                  " .txt file(s) that are not frames of this evaluation (not in the split, or not "
                  "a frame id), first: " +
                  ignored_files.front());
  }
  if (!skipped_lines.empty()) {
    out.push_back("skipped bad lines (--lenient): " + std::to_string(skipped_lines.size()));
  }
  if (!det_not_from_run.empty()) {
    out.push_back("warning: " + std::to_string(det_not_from_run.size()) +
                  " detection file(s) are not from the run in " +
                  (det_dir / kRunManifestFile).string() +
                  " (written or changed by another run; the scores mix runs), first: " +
                  det_not_from_run.front());
  }
  return out;
}

EvalInput LoadEvalFrames(const EvalInputOptions& options) {
  options.Check();
  EvalInput in;
  in.label_dir = LabelDir(options.gt);
  in.det_dir = DetectionDir(options.det);
  std::vector<std::string> label_not_ids;
  const std::set<std::string> label_stems = FrameStems(in.label_dir, &label_not_ids);
  const std::set<std::string> det_stems = FrameStems(in.det_dir, &in.ignored_files);
  std::vector<std::string> ids;
  if (options.split.empty()) {
    for (const std::string& s : det_stems) {
      STEREODET_CHECK_IO(label_stems.count(s))
          << "detection file " << (in.det_dir / (s + ".txt")).string() << " has no label file in "
          << in.label_dir.string()
          << " (with --split, detection files of frames outside the split are ignored)";
    }
    ids.assign(label_stems.begin(), label_stems.end());
  } else {
    ids = ReadIds(options.gt, options.split);
    for (const std::string& id : ids) {
      STEREODET_CHECK_IO(label_stems.count(id))
          << "split " << options.split << ": frame " << id << " has no label file in "
          << in.label_dir.string();
    }
    const std::set<std::string> in_split(ids.begin(), ids.end());
    if (in_split.size() != ids.size()) {
      // A frame listed twice would be evaluated twice and weigh double in every figure.
      std::set<std::string> seen;
      for (const std::string& id : ids) {
        STEREODET_CHECK_IO(seen.insert(id).second)
            << "split " << options.split << ": frame " << id << " is listed more than once";
      }
    }
    std::vector<std::string> outside;
    for (const std::string& s : det_stems) {
      if (!in_split.count(s)) outside.push_back((in.det_dir / (s + ".txt")).string());
    }
    in.ignored_files.insert(in.ignored_files.end(), outside.begin(), outside.end());
    std::sort(in.ignored_files.begin(), in.ignored_files.end());
  }
  in.ignored_files.insert(in.ignored_files.end(), label_not_ids.begin(), label_not_ids.end());
  STEREODET_CHECK_IO(!ids.empty()) << "no frame to evaluate in " << in.label_dir.string();
  if (options.split.empty() && !options.missing_as_empty) {
    // Counted over the whole list, so that every shard of one run decides alike.
    std::vector<std::string> missing;
    for (const std::string& id : ids) {
      if (!det_stems.count(id)) missing.push_back(id);
    }
    STEREODET_CHECK_IO(static_cast<double>(missing.size()) <=
                       kMaxMissingDetectionShare * static_cast<double>(ids.size()))
        << "--det " << in.det_dir.string() << " has no detection file for " << missing.size()
        << " of the " << ids.size() << " labelled frames in " << in.label_dir.string()
        << " (first: " << missing.front() << ".txt). Without --split every label file is a frame "
        << "to evaluate, and these would count as frames where the detector found nothing; pass "
           "--split with the frames that were detected, or --missing-as-empty to evaluate them "
           "so";
  }

  const size_t first = options.shard.Begin(ids.size()), last = options.shard.End(ids.size());
  std::vector<EvalFrameSource> sources(last - first);
  std::vector<ParsedFrame> parsed(sources.size());
  // DIR / "ID.txt" as a string: the same text as the path operator's, without its path objects.
  const std::string label_prefix = (in.label_dir / "").native();
  const std::string det_prefix = (in.det_dir / "").native();
  ParallelFor(
      sources.size(),
      [&](size_t i) {
        EvalFrameSource source;
        source.id = ids[first + i];
        source.label_path.reserve(label_prefix.size() + source.id.size() + 4);
        source.label_path.append(label_prefix).append(source.id).append(".txt");
        source.label_text = ReadFile(source.label_path);
        source.has_detections = det_stems.count(source.id) > 0;
        if (source.has_detections) {
          source.det_path.reserve(det_prefix.size() + source.id.size() + 4);
          source.det_path.append(det_prefix).append(source.id).append(".txt");
          source.det_text = ReadFile(source.det_path);
        }
        parsed[i] = ParseSource(source, options.lenient, options.score_if_missing);
        // Without keep_sources the bytes go now: one frame's at a time per thread.
        if (options.keep_sources) sources[i] = std::move(source);
      },
      options.num_threads);
  FinishFrames(std::move(parsed), &in);
  if (options.keep_sources) in.sources = std::move(sources);
  CheckDetectionRun(in);
  return in;
}

EvalInput EvalInputFromSources(std::vector<EvalFrameSource> sources, bool lenient, int num_threads,
                               bool keep_sources, std::optional<double> score_if_missing) {
  STEREODET_CHECK(num_threads >= 0) << "num_threads = " << num_threads << ", must be >= 0";
  EvalInput in;
  std::vector<ParsedFrame> parsed(sources.size());
  ParallelFor(
      sources.size(),
      [&](size_t i) { parsed[i] = ParseSource(sources[i], lenient, score_if_missing); },
      num_threads);
  FinishFrames(std::move(parsed), &in);
  if (keep_sources) in.sources = std::move(sources);
  return in;
}

}  // namespace stereodet
