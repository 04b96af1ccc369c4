// Shards of a detection run, `detect ssd|det3d|rpn --shard K/N`, and `detect merge`
// (docs/scale.md).
//
// A detection shard is a contiguous range of whole batches of the run's frame list: with B =
// ceil(n / batch_size) batches, shard K/N holds batches [floor(K B / N), floor((K + 1) B / N))
// (util/shard.h over batches), so every batch a shard runs is a batch of one run, the same frames
// in the same positions. Why: the network's floats depend in their last bits on the batch a frame
// is in (LibTorch picks other kernels for other batch sizes; measured on the CPU: a score's sixth
// decimal), so shards of single frames would not give one run's bytes. Shards differ in size by
// at most one batch.
//
// Shard K/N of a detection run writes its own folder, a StagedFolder like one run's (committed
// whole, so a shard folder is either all there or not there): the detection files of its frames,
// a run.json whose frames are its own and whose tool, version, inputs and settings are those of
// the whole run, and detect_shard.json, which names the shard, the batch size and the whole frame
// list (its length and hash). MergeDetections checks that its folders are the N shards of one run
// and writes the folder of that run: the same ID.txt files, byte for byte, and a run.json that
// differs from one run's (of the same batch size) only in its command line (the merge's). A
// one-run folder holds no detect_shard.json.
#ifndef STEREODET_MODELS_DETECT_SHARD_H_
#define STEREODET_MODELS_DETECT_SHARD_H_

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/score_calibration.h"
#include "stereodet/models/detector.h"
#include "stereodet/models/device.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/util/check.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/shard.h"
#include "stereodet/util/timer.h"

namespace stereodet {

// The shard record's file name in a shard folder.
inline constexpr char kDetectShardFile[] = "detect_shard.json";

struct DetectShardRecord {
  std::string tool;         // the run.json tool: "detect ssd", "detect det3d" or "detect rpn"
  Shard shard;              // K/N
  int batch_size = 1;       // frames per forward pass (the shard's range is in whole batches)
  int64_t list_frames = 0;  // frames of the whole list (after --max-frames), all shards together
  std::string list_hash;    // FrameListHash of the whole list
};

// FNV-1a 64 (16 hex digits) of the ids, each followed by '\n', in their order.
std::string FrameListHash(const std::vector<std::string>& ids);

// The shard's frames: its contiguous range of whole batches of `ids` (above; all of `ids` for 1/1,
// and for batch_size 1 the range util/shard.h gives). Throws std::invalid_argument for a shard
// that fails Check() or batch_size < 1.
std::vector<std::string> ShardFrames(const std::vector<std::string>& ids, const Shard& shard,
                                     int batch_size);

// The frame list of a detect run, all shards together: the split's ids (KittiDataset::ReadSplit),
// the first `max_frames` of them when max_frames > 0. Throws std::runtime_error naming the split
// when it lists no frame (nothing would be detected, and an empty folder would look like a run).
std::vector<std::string> DetectFrameList(const KittiDataset& dataset,
                                         const std::filesystem::path& split, int max_frames);

// Writes each result's objects to DIR/ID.txt (KITTI detection files) and adds its stage times to
// `times` ("stereo", "encode", "network", "decode"). Returns the number of objects written.
int64_t WriteDetectResults(const std::vector<DetectResult>& results,
                           const std::filesystem::path& dir, StageTimes& times);

// Writes DIR/detect_shard.json atomically: {"format": 1, "tool", "shard": "K/N", "batch_size",
// "list_frames", "list_fnv1a64"}.
void WriteDetectShardRecord(const std::filesystem::path& dir, const DetectShardRecord& record);
// Reads it back. Throws std::runtime_error naming the folder when the file is missing ("not a
// folder of `detect --shard`"), ParseError naming the file and field when it is not a record.
DetectShardRecord ReadDetectShardRecord(const std::filesystem::path& dir);

// Finishes the folder of a detection run or of one of its shards (`detect ssd|det3d|rpn`): adds
// each of `ids` (the frames this run or shard detected) with the hash of out/ID.txt to
// manifest.frames, writes run.json, the shard record when the shard is Recorded() (a part of
// several, or named on the command line: 0/1 too; its tool that of `manifest`, its frame list
// `all_ids`, before ShardFrames) and commits `out`.
void CommitDetectionFolder(StagedFolder& out, RunManifest manifest,
                           const std::vector<std::string>& ids,
                           const std::vector<std::string>& all_ids, const Shard& shard,
                           int batch_size);

struct MergeDetectionsOptions {
  std::vector<std::filesystem::path> shards;  // the N shard folders, in any order
  std::filesystem::path out_dir;              // receives the folder of one run (replaced whole)
  std::string command_line;                   // for OUT/run.json (empty from a library call)
  void Check() const;                         // throws std::invalid_argument
};

struct MergeDetectionsResult {
  std::string tool;  // the shards' run.json tool
  int shards = 0;
  int frames = 0;
  double seconds = 0;
};

// Before anything is written it throws std::invalid_argument, naming the folder, for a shard
// given twice, a missing shard (by K/N), a shard of another count, batch size or frame list, one
// whose run.json differs from shard 0's in tool, version, inputs or settings, or an out_dir that
// overlaps a shard folder; std::runtime_error for a shard folder that is not one (no
// detect_shard.json, no run.json), an out_dir that is a folder of something else, and a detection
// file whose bytes are not those its run.json records (changed since its shard ran). Then it
// writes OUT as a StagedFolder (an earlier detection folder there is replaced whole): every
// frame's file, copied, and run.json with the frames of all shards in list order.
MergeDetectionsResult MergeDetections(const MergeDetectionsOptions& options);

// Runs prepare(k) and then consume(k) for k = 0 .. num_batches - 1, consume in order of k on the
// calling thread. With `overlap`, prepare(k + 1) runs on a second thread while consume(k) runs (one
// batch ahead at most), so prepare(k) and consume(k - 1) must not share state (two slots, k % 2).
// An exception of either is rethrown here, after the other has finished; no later batch starts.
void RunTwoStagePipeline(int num_batches, bool overlap, const std::function<void(int)>& prepare,
                         const std::function<void(int)>& consume);

// The options every batch detection command shares (`detect ssd|rpn|det3d`): DetectSsdOptions,
// DetectRpnOptions and DetectDet3dOptions are these plus their family's own. A family's default
// batch size is its own (given to the constructor).
struct DetectionRunOptions {
  explicit DetectionRunOptions(int default_batch_size) : batch_size(default_batch_size) {}

  std::filesystem::path model_dir;  // written by `stereodet train FAMILY`
  std::filesystem::path data_root;  // KITTI layout
  std::string subset = "training";  // "training" or "testing"
  std::string split = "val";        // ImageSets/SPLIT.txt, or a path to a split file
  std::filesystem::path out_dir;    // receives ID.txt per frame
  int batch_size;                   // frames per forward pass
  int threads = 0;                  // LibTorch and the per-frame preparation (0 = all cores)
  int max_frames = 0;               // only the first N frames of the split (0 = all)
  // Only shard K/N of those frames (after max_frames), in whole batches (above); 1/1 = all. A
  // shard's folder also holds detect_shard.json, for `detect merge`; its detection files are those
  // of one run of the same batch_size.
  Shard shard;
  std::string device = "cpu";  // cpu | cuda (device.h)
  ProgressOptions progress;
  std::string command_line;  // for OUT/run.json (empty from a library call)
  // A score calibration file (`stereodet calibrate --fit`, kitti/score_calibration.h): every
  // detection of a calibrated class is written with its calibrated probability (after the score
  // threshold, which applies to the raw scores). Empty: the raw scores.
  std::filesystem::path calibration;

  // --model, --data and --out given, batch size >= 1, threads and max frames >= 0, the shard, a
  // known device. Throws std::invalid_argument naming the field. A family's Check calls it.
  void Check() const;
};

// run.json's fixed part for a detection run: its tool ("detect rpn"), this build's version, the
// command line and the inputs model, data, subset and split (a family adds its own).
RunManifest DetectionManifest(const std::string& tool, const std::string& command_line,
                              const std::filesystem::path& model_dir,
                              const std::filesystem::path& data_root, const std::string& subset,
                              const std::string& split);

// What a batch detection command (`detect ssd|rpn|det3d`) did.
struct DetectSummary {
  int frames = 0;          // this shard's
  int64_t detections = 0;  // objects written
  double seconds = 0;      // end to end: opening the model, reading, stereo, network, writing
  double frames_per_second = 0;
  std::string stage_times;  // StageTimes::Format(): read, the detector's stages, write
};

// What the three batch detection commands (`detect ssd|rpn|det3d`) do around their frames.
class DetectionRun {
  // Made first (members are made in declaration order), so that DetectSummary::seconds counts
  // opening the output folder and the model too.
  Timer timer_;

 public:
  // Checks --out against the inputs (--data's subset and ImageSets, --model, and `more_inputs`,
  // each (flag, path)), opens the output folder (anything but an earlier detection folder is
  // refused before any work), opens the `family` detector ("ssd", "rpn", "det3d") with
  // `detector_options` and the run's device, threads and calibration, and lists the run's frames
  // and this shard's. Throws what those throw, naming the file or the flag.
  DetectionRun(const DetectionRunOptions& o, const std::string& family,
               DetectorOptions detector_options,
               const std::vector<std::pair<std::string, std::filesystem::path>>& more_inputs = {});

  // Detects this shard's frames (`ids`) batch by batch and writes each frame's objects to
  // out/ID.txt: `read(id, frame)` fills a frame (a batch's frames in parallel, on the run's
  // threads), then Detector::Prepare and Run. With `overlap`, the next batch is read and prepared
  // while the network runs on this one (RunTwoStagePipeline; the same bytes either way). Times
  // the stages ("read", the detector's, "write") for the summary; returns the objects written.
  int64_t DetectFrames(const std::function<void(const std::string& id, StereoFrame& frame)>& read,
                       bool overlap);

  // Writes run.json (the tool, version, command line, the inputs model, data, subset, split and
  // `more_inputs`, each frame's hash, settings {"model_weights_fnv1a64": the detector's, then
  // `settings`: more JSON fields, without braces}) and, for a shard, its record; commits the
  // folder. Returns the run's summary (after DetectFrames).
  DetectSummary Commit(const std::vector<std::pair<std::string, std::string>>& more_inputs,
                       const std::string& settings);

  StagedFolder out;
  Detector detector;
  KittiDataset dataset;
  std::vector<std::string> all_ids;  // the run's frames, all shards together (DetectFrameList)
  std::vector<std::string> ids;      // this shard's (ShardFrames)

 private:
  static std::filesystem::path CheckedOutputDir(
      const std::filesystem::path& out_dir, const std::filesystem::path& data_root,
      const std::string& subset, const std::filesystem::path& model_dir,
      const std::vector<std::pair<std::string, std::filesystem::path>>& more_inputs);
  // `detector_options` with the run's device, threads and calibration file (the Detector applies
  // it to every frame's objects).
  static DetectorOptions WithDevice(DetectorOptions options, const DetectionRunOptions& o);

  RunManifest manifest_;
  Shard shard_;
  int batch_size_;
  int threads_;
  ProgressOptions progress_;
  StageTimes times_;
  int64_t detections_ = 0;
};

// Reads the right image and the calibration of `frame` (its left image read already) for stereo
// matching with `disparity`, checking that the two images have one size and that the matcher fits
// it. Throws std::runtime_error naming the file.
void ReadStereoPairFiles(const FramePaths& paths, const DisparityOptions& disparity,
                         StereoFrame& frame);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DETECT_SHARD_H_
