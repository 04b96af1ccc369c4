// Output folders that know their owner. Every command that writes a folder marks it as its own:
// run.json's "tool" (detect, train, stereo), results.json (eval), sweep.csv and compare.csv
// (eval sweep, eval compare), stereo.json (stereo),
// synth_settings.txt (synth), an index.html with the report's figure data (report). A command
// replaces, resumes or writes into a folder only when the folder is absent, empty, or marked by a
// command whose output it may replace; anything else (a model, a KITTI data set, another command's
// output, someone's files) is refused before any work, naming what was found. `StagedFolder`
// (below) and the in-place writers (train, stereo, synth) all go through `CheckOutputFolderOwner`.
#ifndef STEREODET_UTIL_OUTPUT_FOLDER_H_
#define STEREODET_UTIL_OUTPUT_FOLDER_H_

#include <filesystem>
#include <string>
#include <vector>

namespace stereodet {

// The makers a command names in CheckOutputFolderOwner: a run.json's tool ("detect ssd",
// "train rpn", "stereo"), or one of these for the folders that carry another marker.
inline constexpr char kMakerEval[] = "eval";             // results.json
inline constexpr char kMakerSweep[] = "eval sweep";      // sweep.csv
inline constexpr char kMakerCompare[] = "eval compare";  // compare.csv
inline constexpr char kMakerReport[] = "report";         // index.html with "stereodet-figures"
inline constexpr char kMakerStereo[] = "stereo";         // stereo.json (and run.json's tool)
inline constexpr char kMakerSynth[] = "synth";           // synth_settings.txt

// What a folder is, as far as its marker files and its layout tell.
struct OutputFolderIdentity {
  enum class State {
    kAbsent,   // no such path
    kEmpty,    // a folder with nothing in it (our own leftover temporaries aside)
    kMarked,   // made by one command: `maker`
    kForeign,  // anything else: a model without a training record, a KITTI data set, other files
  };
  State state = State::kAbsent;
  std::string maker;        // for kMarked: the command that made it (see the constants above)
  std::string description;  // for messages: "a model folder (model.json, model.pt; run.json of
                            // 'train ssd')", "a KITTI data set (it holds training/)", ...
};

// Identifies `dir` without changing it. Throws std::runtime_error naming `dir` if it exists and is
// not a folder, or cannot be listed.
//
// The rules, in order: a folder holding model.json, model.pt or checkpoint.pt is a model folder,
// marked by "train ARCH" when its run.json says so (or, without run.json, its model.json's
// architecture) and foreign otherwise; a folder with markers of two different commands is foreign
// (a mixed folder); one maker's markers mark it, except that a folder laid out like a KITTI data
// set (training/, testing/, ImageSets/, or two of image_2/, image_3/, calib/, label_2/,
// velodyne/) is foreign unless synth or stereo made it; a folder with none of these is foreign.
OutputFolderIdentity IdentifyOutputFolder(const std::filesystem::path& dir);

// Throws std::runtime_error unless `dir` is absent, an empty folder, or marked by one of `makers`:
// "detect ssd: --out models/ssd-rgb is a model folder (model.json, model.pt; run.json of 'train
// ssd'); detect ssd replaces only a folder that detect ssd, detect rpn or detect det3d made, or an
// empty one: give a new or empty folder". `command` names the caller in the message.
void CheckOutputFolderOwner(const std::filesystem::path& dir, const std::string& command,
                            const std::vector<std::string>& makers);

// The makers of detection folders (detect ssd|rpn|det3d, run --kitti-out; detect merge keeps its
// shards' tool): each of these commands may replace any of them, as they are one kind of folder.
const std::vector<std::string>& DetectionFolderMakers();

// Removes the leftovers of runs that died before they could clean up after themselves: hidden
// siblings `.NAME.staging-PID-N` and `.NAME.old-PID-N` of `dir`, and with `inside` the
// `.FILE.tmp-PID-N` files at any depth inside it, whose process PID runs no more and which nothing
// has written into for 10 minutes (a run on another host sharing the folder has PIDs that mean
// nothing here). Best effort: never throws. A live run (its PID running, or still writing) is left
// alone.
void RemoveStaleTemporaries(const std::filesystem::path& dir, bool inside = true);

// An output folder written as one run. Files go into a hidden staging folder beside `final_dir`
// (`.NAME.staging-PID-N`); Commit() puts it in place of `final_dir` with two renames (an existing
// `final_dir` is renamed aside, then removed). So the folder never mixes the files of two runs, two
// runs into one folder cannot interleave (the last to commit wins, whole), and an interrupted run
// leaves the previous folder as it was. Without Commit() the destructor removes the staging folder.
//
//   StagedFolder out(dir, "eval", {kMakerEval});
//   WriteFileAtomically(out.path() / "results.json", ...);
//   out.Commit();
class StagedFolder {
 public:
  // Throws std::runtime_error, naming the folder and what it holds, unless `final_dir` is absent,
  // empty or marked by one of `makers` (CheckOutputFolderOwner), so that a folder this command did
  // not make is never replaced. Stale leftovers of killed runs beside it are removed first.
  StagedFolder(std::filesystem::path final_dir, const std::string& command,
               const std::vector<std::string>& makers);
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

}  // namespace stereodet

#endif  // STEREODET_UTIL_OUTPUT_FOLDER_H_
