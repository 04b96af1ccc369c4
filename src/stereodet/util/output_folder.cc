#include "stereodet/util/output_folder.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string_view>
#include <system_error>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/run_manifest.h"

namespace stereodet {
namespace fs = std::filesystem;

namespace {

// `dir` without a trailing separator, so that filename() names the folder itself.
fs::path WithoutTrailingSeparator(fs::path dir) {
  dir = dir.lexically_normal();
  if (!dir.has_filename() && dir.has_parent_path()) dir = dir.parent_path();
  return dir;
}

// The PID in a temporary's name `.NAME.KIND-PID-N[.EXT]`, if `name` is one of `kind`.
std::optional<pid_t> TemporaryPid(std::string_view name, std::string_view kind) {
  if (name.empty() || name.front() != '.') return std::nullopt;
  const std::string tag = "." + std::string(kind) + "-";
  const size_t at = name.rfind(tag);
  if (at == std::string_view::npos) return std::nullopt;
  const std::string_view rest = name.substr(at + tag.size());
  long long pid = 0;
  const auto [end, ec] = std::from_chars(rest.data(), rest.data() + rest.size(), pid);
  if (ec != std::errc() || end == rest.data() || end == rest.data() + rest.size() || *end != '-' ||
      pid <= 0) {
    return std::nullopt;
  }
  return static_cast<pid_t>(pid);
}

// One of our own temporary files (AtomicPath's): a leftover of a run, never a user's file.
bool IsOwnTemporary(std::string_view name) { return TemporaryPid(name, "tmp").has_value(); }

bool ProcessRuns(pid_t pid) { return ::kill(pid, 0) == 0 || errno == EPERM; }

// A leftover is stale when its PID runs no process here and nothing was written into it for this
// long: a run on another host sharing the folder (a Dask cluster on a shared file system) has PIDs
// that mean nothing here, but a live run keeps writing (a staging folder's time changes with each
// file added to it; a temporary file is written in one go).
constexpr auto kStaleAfter = std::chrono::minutes(10);

bool IsStale(const fs::path& path, pid_t pid) {
  if (ProcessRuns(pid)) return false;
  std::error_code ec;
  const fs::file_time_type written = fs::last_write_time(path, ec);
  return !ec && fs::file_time_type::clock::now() - written > kStaleAfter;
}

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}
bool IsFolder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// The maker a run.json names, or the reason it names none.
struct RunJsonMaker {
  std::string tool;
  std::string problem;  // non-empty when the file is there but unreadable
};
std::optional<RunJsonMaker> ReadRunJsonMaker(const fs::path& dir) {
  if (!fs::exists(dir / kRunManifestFile)) return std::nullopt;
  try {
    const std::optional<RunManifest> manifest = ReadRunManifest(dir);
    return RunJsonMaker{manifest ? manifest->tool : "", ""};
  } catch (const std::exception&) {
    return RunJsonMaker{"", "an unreadable run.json"};
  }
}

// model.json's "architecture" ("ssd", "rpn", "det3d"), or empty.
std::string ModelArchitecture(const fs::path& dir) {
  try {
    const auto j = nlohmann::json::parse(ReadFile(dir / "model.json"));
    if (j.is_object() && j.contains("architecture") && j["architecture"].is_string()) {
      return j["architecture"].get<std::string>();
    }
  } catch (const std::exception&) {
  }
  return "";
}

// Whether an index.html is a report of ours (it embeds its figures' data under this id).
bool IsOurReport(const fs::path& index) {
  try {
    return ReadFile(index).find("id=\"stereodet-figures\"") != std::string::npos;
  } catch (const std::exception&) {
    return false;
  }
}

std::string Join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += separator;
    out += items[i];
  }
  return out;
}

// "a, b or c"
std::string JoinOr(const std::vector<std::string>& items) {
  if (items.size() <= 1) return Join(items, "");
  std::vector<std::string> head(items.begin(), items.end() - 1);
  return Join(head, ", ") + " or " + items.back();
}

}  // namespace

OutputFolderIdentity IdentifyOutputFolder(const fs::path& dir_in) {
  const fs::path dir = WithoutTrailingSeparator(dir_in);
  OutputFolderIdentity identity;
  std::error_code ec;
  const fs::file_status status = fs::status(dir, ec);
  if (!fs::exists(status)) {
    identity.state = OutputFolderIdentity::State::kAbsent;
    identity.description = "absent";
    return identity;
  }
  STEREODET_CHECK_IO(fs::is_directory(status)) << dir.string() << " exists and is not a folder";
  std::vector<std::string> names;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (!IsOwnTemporary(name)) names.push_back(name);
  }
  STEREODET_CHECK_IO(!ec) << "cannot list " << dir.string() << ": " << ec.message();
  std::sort(names.begin(), names.end());
  if (names.empty()) {
    identity.state = OutputFolderIdentity::State::kEmpty;
    identity.description = "an empty folder";
    return identity;
  }
  identity.state = OutputFolderIdentity::State::kForeign;

  // The markers, each naming the command that writes it.
  std::set<std::string> makers;
  std::vector<std::string> evidence;
  const std::optional<RunJsonMaker> run = ReadRunJsonMaker(dir);
  if (run) {
    if (!run->problem.empty()) {
      evidence.push_back(run->problem);
    } else {
      makers.insert(run->tool);
      evidence.push_back("run.json of '" + run->tool + "'");
    }
  }
  if (IsFile(dir / "results.json")) {
    makers.insert(kMakerEval);
    evidence.push_back("results.json of eval");
  }
  if (IsFile(dir / "sweep.csv")) {
    makers.insert(kMakerSweep);
    evidence.push_back("sweep.csv of eval sweep");
  }
  if (IsFile(dir / "compare.csv")) {
    makers.insert(kMakerCompare);
    evidence.push_back("compare.csv of eval compare");
  }
  if (IsFile(dir / "stereo.json")) {
    makers.insert(kMakerStereo);
    evidence.push_back("stereo.json of stereo");
  }
  if (IsFile(dir / "synth_settings.txt")) {
    makers.insert(kMakerSynth);
    evidence.push_back("synth_settings.txt of synth");
  }
  if (IsFile(dir / "index.html") && IsOurReport(dir / "index.html")) {
    makers.insert(kMakerReport);
    evidence.push_back("index.html of report");
  }

  std::vector<std::string> model_files;
  for (const char* file : {"model.json", "model.pt", "checkpoint.pt"}) {
    if (fs::exists(dir / file)) model_files.emplace_back(file);
  }
  std::vector<std::string> kitti_folders;
  for (const char* folder : {"training", "testing", "ImageSets"}) {
    if (IsFolder(dir / folder)) kitti_folders.push_back(std::string(folder) + "/");
  }
  std::vector<std::string> frame_folders;
  for (const char* folder : {"image_2", "image_3", "calib", "label_2", "velodyne"}) {
    if (IsFolder(dir / folder)) frame_folders.push_back(std::string(folder) + "/");
  }
  if (frame_folders.size() >= 2) {
    kitti_folders.insert(kitti_folders.end(), frame_folders.begin(), frame_folders.end());
  }

  const std::string markers = evidence.empty() ? "" : "; " + Join(evidence, ", ");
  if (!model_files.empty()) {
    identity.description = "a model folder (" + Join(model_files, ", ") + markers + ")";
    std::string trainer;
    if (!run) {
      const std::string architecture = ModelArchitecture(dir);
      if (!architecture.empty()) trainer = "train " + architecture;
    } else if (run->tool.rfind("train ", 0) == 0) {
      trainer = run->tool;
    }
    if (!trainer.empty() &&
        (makers.empty() || (makers.size() == 1 && *makers.begin() == trainer))) {
      identity.state = OutputFolderIdentity::State::kMarked;
      identity.maker = trainer;
    }
    return identity;
  }
  if (makers.size() > 1) {
    identity.description =
        "a folder mixing the outputs of several commands (" + Join(evidence, ", ") + ")";
    return identity;
  }
  if (!kitti_folders.empty()) {
    identity.description =
        "a KITTI data set (it holds " + Join(kitti_folders, ", ") + markers + ")";
    if (makers.size() == 1 && (*makers.begin() == kMakerSynth || *makers.begin() == kMakerStereo)) {
      identity.state = OutputFolderIdentity::State::kMarked;
      identity.maker = *makers.begin();
      identity.description = "the output of " + identity.maker + " (" + Join(evidence, ", ") + ")";
    }
    return identity;
  }
  if (makers.size() == 1) {
    identity.state = OutputFolderIdentity::State::kMarked;
    identity.maker = *makers.begin();
    identity.description = "the output of " + identity.maker + " (" + Join(evidence, ", ") + ")";
    return identity;
  }
  std::vector<std::string> shown(names.begin(), names.begin() + std::min<size_t>(names.size(), 3));
  identity.description = "a folder of other files (" + Join(shown, ", ") +
                         (names.size() > shown.size() ? ", ..." : "") + markers + ")";
  return identity;
}

void CheckOutputFolderOwner(const fs::path& dir, const std::string& command,
                            const std::vector<std::string>& makers) {
  const OutputFolderIdentity identity = IdentifyOutputFolder(dir);
  using State = OutputFolderIdentity::State;
  if (identity.state == State::kAbsent || identity.state == State::kEmpty) return;
  if (identity.state == State::kMarked &&
      std::find(makers.begin(), makers.end(), identity.maker) != makers.end()) {
    return;
  }
  STEREODET_THROW_IO() << command << ": " << WithoutTrailingSeparator(dir).string() << " is "
                       << identity.description << "; " << command
                       << " replaces or writes into only a folder that " << JoinOr(makers)
                       << " made, or an empty one: give a new or empty folder";
}

const std::vector<std::string>& DetectionFolderMakers() {
  static const std::vector<std::string> makers = {"detect ssd", "detect rpn", "detect det3d",
                                                  "run"};
  return makers;
}

void RemoveStaleTemporaries(const fs::path& dir_in, bool inside) {
  const fs::path dir = WithoutTrailingSeparator(dir_in);
  std::error_code ec;
  // Siblings: `.NAME.staging-PID-N`, `.NAME.old-PID-N` of this folder.
  const std::string prefix = "." + dir.filename().string() + ".";
  const fs::path parent = dir.has_parent_path() ? dir.parent_path() : fs::path(".");
  for (fs::directory_iterator it(parent, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string_view rest = std::string_view(name).substr(prefix.size() - 1);
    for (const char* kind : {"staging", "old"}) {
      const std::optional<pid_t> pid = TemporaryPid(rest, kind);
      if (pid && IsStale(it->path(), *pid)) {
        std::error_code ignored;
        fs::remove_all(it->path(), ignored);
      }
    }
  }
  // Inside: `.FILE.tmp-PID-N[.EXT]` at any depth (stereo and synth write into subfolders).
  if (!inside || !IsFolder(dir)) return;
  std::vector<fs::path> stale;
  ec.clear();
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::optional<pid_t> pid = TemporaryPid(it->path().filename().string(), "tmp");
    if (pid && IsStale(it->path(), *pid)) stale.push_back(it->path());
  }
  for (const fs::path& p : stale) {
    std::error_code ignored;
    fs::remove(p, ignored);
  }
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

}  // namespace

StagedFolder::StagedFolder(fs::path final_dir, const std::string& command,
                           const std::vector<std::string>& makers)
    : final_dir_(WithoutTrailingSeparator(std::move(final_dir))) {
  CheckOutputFolderOwner(final_dir_, command, makers);
  // Only the siblings: nothing is written inside `final_dir`, which is replaced whole.
  RemoveStaleTemporaries(final_dir_, /*inside=*/false);
  staging_dir_ = SiblingName(final_dir_, "staging");
  std::error_code ec;
  fs::create_directories(staging_dir_, ec);
  STEREODET_CHECK_IO(!ec) << command << ": cannot create the staging folder "
                          << staging_dir_.string() << " beside " << final_dir_.string() << ": "
                          << ec.message() << " (the folder that holds the output must be writable)";
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

}  // namespace stereodet
