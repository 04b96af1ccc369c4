#include "stereodet/models/detect_shard.h"

#include <algorithm>
#include <future>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <utility>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/model_json_internal.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kDetectShardFormat = 1;

struct ShardFolder {
  fs::path dir;
  DetectShardRecord record;
  RunManifest manifest;
};

// The shards' run.json must agree in everything but the command line and the frames.
void CheckSameRun(const ShardFolder& a, const ShardFolder& b) {
  const auto differs = [&](const char* what, const std::string& x, const std::string& y) {
    STEREODET_CHECK(x == y) << "detect merge: " << b.dir.string() << "/run.json has another "
                            << what << " than " << a.dir.string() << "/run.json (" << y << " vs "
                            << x << "); the shards are not of one run";
  };
  differs("tool", a.manifest.tool, b.manifest.tool);
  differs("version", a.manifest.version, b.manifest.version);
  differs("settings", a.manifest.settings_json, b.manifest.settings_json);
  const auto inputs = [](const RunManifest& m) {
    std::string text;
    for (const auto& [name, path] : m.inputs) text += name + "=" + path + " ";
    return text;
  };
  differs("inputs", inputs(a.manifest), inputs(b.manifest));
}

}  // namespace

std::string FrameListHash(const std::vector<std::string>& ids) {
  uint64_t hash = kFnv1a64Offset;
  for (const std::string& id : ids) {
    hash = Fnv1a64(id, hash);
    hash = Fnv1a64("\n", hash);
  }
  return HashHex(hash);
}

namespace {

// [begin, end) of the shard's frames in a list of n.
std::pair<size_t, size_t> ShardRange(size_t n, const Shard& shard, int batch_size) {
  shard.Check();
  STEREODET_CHECK(batch_size >= 1) << "batch size must be >= 1, got " << batch_size;
  const size_t batch = static_cast<size_t>(batch_size);
  const size_t batches = (n + batch - 1) / batch;
  return {std::min(n, shard.Begin(batches) * batch), std::min(n, shard.End(batches) * batch)};
}

}  // namespace

std::vector<std::string> ShardFrames(const std::vector<std::string>& ids, const Shard& shard,
                                     int batch_size) {
  const auto [begin, end] = ShardRange(ids.size(), shard, batch_size);
  return {ids.begin() + static_cast<std::ptrdiff_t>(begin),
          ids.begin() + static_cast<std::ptrdiff_t>(end)};
}

void WriteDetectShardRecord(const fs::path& dir, const DetectShardRecord& record) {
  json j;
  j["format"] = kDetectShardFormat;
  j["tool"] = record.tool;
  j["shard"] = ShardName(record.shard);
  j["batch_size"] = record.batch_size;
  j["list_frames"] = record.list_frames;
  j["list_fnv1a64"] = record.list_hash;
  WriteFileAtomically(dir / kDetectShardFile, j.dump(2) + "\n");
}

DetectShardRecord ReadDetectShardRecord(const fs::path& dir) {
  const fs::path path = dir / kDetectShardFile;
  STEREODET_CHECK_IO(fs::is_regular_file(path))
      << dir.string() << " holds no " << kDetectShardFile
      << ": not a folder of `detect ssd|det3d --shard K/N`";
  const std::string file = path.string();
  json j;
  try {
    j = json::parse(ReadFile(path));
  } catch (const json::parse_error& e) {
    throw ParseError(file, 0, "json", e.what());
  }
  DetectShardRecord record;
  std::string field = "format";
  try {
    if (internal::JsonInt(j, field, file) != kDetectShardFormat) {
      throw ParseError(file, 0, field,
                       "format " + j.at(field).dump() + ", this version reads " +
                           std::to_string(kDetectShardFormat));
    }
    field = "tool";
    record.tool = j.at(field).get<std::string>();
    field = "shard";
    const std::optional<Shard> shard = ParseShard(j.at(field).get<std::string>());
    if (!shard) throw ParseError(file, 0, field, "not K/N: " + j.at(field).dump());
    record.shard = *shard;
    field = "batch_size";
    record.batch_size = internal::JsonInt(j, field, file);
    if (record.batch_size < 1) throw ParseError(file, 0, field, "must be >= 1");
    field = "list_frames";
    record.list_frames = j.at(field).get<int64_t>();
    if (record.list_frames < 0) throw ParseError(file, 0, field, "negative");
    field = "list_fnv1a64";
    record.list_hash = j.at(field).get<std::string>();
  } catch (const json::exception& e) {
    throw ParseError(file, 0, field, e.what());
  }
  return record;
}

std::vector<std::string> DetectFrameList(const KittiDataset& dataset, const fs::path& split,
                                         int max_frames) {
  std::vector<std::string> ids = dataset.ReadSplit(split);
  STEREODET_CHECK_IO(!ids.empty())
      << "the split " << split.string() << " of " << dataset.root().string()
      << " lists no frames: nothing to detect";
  if (max_frames > 0 && static_cast<int>(ids.size()) > max_frames) ids.resize(max_frames);
  return ids;
}

int64_t WriteDetectResults(const std::vector<DetectResult>& results, const fs::path& dir,
                           StageTimes& times) {
  int64_t objects = 0;
  for (const DetectResult& r : results) {
    times.Add("stereo", r.times.stereo_s);
    times.Add("encode", r.times.encode_s);
    times.Add("network", r.times.network_s);
    times.Add("decode", r.times.decode_s);
    WriteObjects(dir / (r.id + ".txt"), r.objects);
    objects += static_cast<int64_t>(r.objects.size());
  }
  return objects;
}

void CommitDetectionFolder(StagedFolder& out, RunManifest manifest,
                           const std::vector<std::string>& ids,
                           const std::vector<std::string>& all_ids, const Shard& shard,
                           int batch_size) {
  for (const std::string& id : ids) {
    manifest.frames.emplace_back(id, HashFileHex(out.path() / (id + ".txt")));
  }
  WriteRunManifest(out.path(), manifest);
  if (shard.Recorded()) {
    WriteDetectShardRecord(out.path(),
                           {manifest.tool, shard, batch_size, static_cast<int64_t>(all_ids.size()),
                            FrameListHash(all_ids)});
  }
  out.Commit();
}

void MergeDetectionsOptions::Check() const {
  STEREODET_CHECK(!shards.empty()) << "detect merge: no shard folder given";
  STEREODET_CHECK(!out_dir.empty()) << "detect merge: --out is required";
}

MergeDetectionsResult MergeDetections(const MergeDetectionsOptions& options) {
  options.Check();
  const Timer timer;
  std::vector<ShardFolder> shards;
  for (const fs::path& dir : options.shards) {
    ShardFolder s{dir, ReadDetectShardRecord(dir), {}};
    std::optional<RunManifest> manifest = ReadRunManifest(dir);
    STEREODET_CHECK_IO(manifest.has_value())
        << dir.string() << " holds no run.json: not a committed detection shard folder";
    s.manifest = std::move(*manifest);
    shards.push_back(std::move(s));
  }
  std::stable_sort(shards.begin(), shards.end(), [](const ShardFolder& a, const ShardFolder& b) {
    return a.record.shard.index < b.record.shard.index;
  });
  const ShardFolder& first = shards.front();
  const int n = first.record.shard.count;
  for (size_t k = 0; k < shards.size(); ++k) {
    const ShardFolder& s = shards[k];
    STEREODET_CHECK(s.record.shard.count == n)
        << "detect merge: " << s.dir.string() << " is shard " << ShardName(s.record.shard)
        << ", but " << first.dir.string() << " is one of " << n;
    STEREODET_CHECK(s.record.shard.index >= static_cast<int>(k))
        << "detect merge: shard " << ShardName(s.record.shard) << " is given twice (at "
        << shards[k - 1].dir.string() << " and " << s.dir.string() << ")";
    STEREODET_CHECK(s.record.shard.index == static_cast<int>(k))
        << "detect merge: shard " << k << "/" << n << " is missing (the next given is "
        << ShardName(s.record.shard) << ", at " << s.dir.string() << ")";
    STEREODET_CHECK(s.record.batch_size == first.record.batch_size)
        << "detect merge: " << s.dir.string() << " ran batches of " << s.record.batch_size
        << " frames, " << first.dir.string() << " of " << first.record.batch_size
        << "; the shards are not of one run";
    STEREODET_CHECK(s.record.tool == first.record.tool &&
                    s.record.list_frames == first.record.list_frames &&
                    s.record.list_hash == first.record.list_hash)
        << "detect merge: " << s.dir.string() << " is a shard of another frame list ("
        << s.record.list_frames << " frames, hash " << s.record.list_hash << ") than "
        << first.dir.string() << " (" << first.record.list_frames << " frames, hash "
        << first.record.list_hash << ")";
    STEREODET_CHECK(s.manifest.tool == s.record.tool)
        << "detect merge: " << s.dir.string() << "/run.json is of '" << s.manifest.tool << "', its "
        << kDetectShardFile << " of '" << s.record.tool << "'";
    CheckSameRun(first, s);
    const auto [begin, end] =
        ShardRange(static_cast<size_t>(s.record.list_frames), s.record.shard, s.record.batch_size);
    const size_t expected = end - begin;
    STEREODET_CHECK_IO(s.manifest.frames.size() == expected)
        << s.dir.string() << "/run.json lists " << s.manifest.frames.size() << " frames; shard "
        << ShardName(s.record.shard) << " of " << s.record.list_frames << " has " << expected;
  }
  STEREODET_CHECK(static_cast<int>(shards.size()) == n)
      << "detect merge: " << shards.size() << " shard folders for " << n << " shards; shard "
      << shards.size() << "/" << n << " is missing";

  RunManifest merged = first.manifest;
  merged.command_line = options.command_line;
  merged.frames.clear();
  std::vector<const fs::path*> frame_dirs;
  for (const ShardFolder& s : shards) {
    for (const auto& frame : s.manifest.frames) {
      merged.frames.push_back(frame);
      frame_dirs.push_back(&s.dir);
    }
  }
  std::vector<std::string> ids;
  ids.reserve(merged.frames.size());
  for (const auto& frame : merged.frames) ids.push_back(frame.first);
  STEREODET_CHECK_IO(FrameListHash(ids) == first.record.list_hash)
      << "detect merge: the shards' frames (" << ids.size() << ", in shard order) are not the "
      << "list their " << kDetectShardFile << " records (hash " << first.record.list_hash << ")";

  std::vector<std::pair<std::string, fs::path>> inputs;
  for (const ShardFolder& s : shards) inputs.emplace_back("shard", s.dir);
  CheckOutputDoesNotOverlapInputs("--out", options.out_dir, inputs);
  StagedFolder out(options.out_dir, "detect merge", DetectionFolderMakers());
  for (size_t i = 0; i < merged.frames.size(); ++i) {
    const auto& [id, hash] = merged.frames[i];
    const fs::path source = *frame_dirs[i] / (id + ".txt");
    const std::string bytes = ReadFile(source);
    STEREODET_CHECK_IO(HashHex(Fnv1a64(bytes)) == hash)
        << "detect merge: " << source.string() << " is not the file its run.json records (hash "
        << HashHex(Fnv1a64(bytes)) << ", recorded " << hash << "); it changed since its shard ran";
    WriteFileAtomically(out.path() / (id + ".txt"), bytes);
  }
  WriteRunManifest(out.path(), merged);
  out.Commit();

  MergeDetectionsResult result;
  result.tool = merged.tool;
  result.shards = n;
  result.frames = static_cast<int>(merged.frames.size());
  result.seconds = timer.ElapsedSeconds();
  return result;
}

void RunTwoStagePipeline(int num_batches, bool overlap, const std::function<void(int)>& prepare,
                         const std::function<void(int)>& consume) {
  if (!overlap) {
    for (int k = 0; k < num_batches; ++k) {
      prepare(k);
      consume(k);
    }
    return;
  }
  if (num_batches <= 0) return;
  prepare(0);
  for (int k = 0; k < num_batches; ++k) {
    // A thread per batch: the batches are large (the network's batch of frames), so starting one
    // costs nothing next to them, and std::async's future rethrows the preparation's exception.
    std::future<void> next;
    if (k + 1 < num_batches) next = std::async(std::launch::async, prepare, k + 1);
    try {
      consume(k);
    } catch (...) {
      if (next.valid()) next.wait();  // the preparation uses the caller's state: let it finish
      throw;
    }
    if (next.valid()) next.get();
  }
}

RunManifest DetectionManifest(const std::string& tool, const std::string& command_line,
                              const std::filesystem::path& model_dir,
                              const std::filesystem::path& data_root, const std::string& subset,
                              const std::string& split) {
  RunManifest manifest;
  manifest.tool = tool;
  manifest.version = StereodetVersion();
  manifest.command_line = command_line;
  manifest.inputs = {{"model", model_dir.string()},
                     {"data", data_root.string()},
                     {"subset", subset},
                     {"split", split}};
  return manifest;
}

void DetectionRunOptions::Check() const {
  STEREODET_CHECK(!model_dir.empty()) << "--model is required";
  STEREODET_CHECK(!data_root.empty()) << "--data is required";
  STEREODET_CHECK(!out_dir.empty()) << "--out is required";
  STEREODET_CHECK(batch_size >= 1) << "batch size must be >= 1, got " << batch_size;
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
  STEREODET_CHECK(max_frames >= 0) << "max_frames must be >= 0, got " << max_frames;
  shard.Check();
  STEREODET_CHECK(ParseComputeDevice(device).has_value())
      << "unknown device '" << device << "' (expected cpu or cuda)";
}

DetectionRun::DetectionRun(
    const DetectionRunOptions& o, const std::string& family, DetectorOptions detector_options,
    const std::vector<std::pair<std::string, std::filesystem::path>>& more_inputs)
    : out(CheckedOutputDir(o.out_dir, o.data_root, o.subset, o.model_dir, more_inputs),
          "detect " + family, DetectionFolderMakers()),
      detector(
          OpenDetectorOfFamily(o.model_dir, WithDevice(std::move(detector_options), o), family)),
      dataset(o.data_root, o.subset),
      all_ids(DetectFrameList(dataset, o.split, o.max_frames)),
      ids(ShardFrames(all_ids, o.shard, o.batch_size)),
      manifest_(DetectionManifest("detect " + family, o.command_line, o.model_dir, o.data_root,
                                  o.subset, o.split)),
      shard_(o.shard),
      batch_size_(o.batch_size),
      threads_(o.threads),
      progress_(o.progress) {}

std::filesystem::path DetectionRun::CheckedOutputDir(
    const std::filesystem::path& out_dir, const std::filesystem::path& data_root,
    const std::string& subset, const std::filesystem::path& model_dir,
    const std::vector<std::pair<std::string, std::filesystem::path>>& more_inputs) {
  std::vector<std::pair<std::string, std::filesystem::path>> inputs = {
      {"--data", data_root / subset}, {"--data", data_root / "ImageSets"}, {"--model", model_dir}};
  inputs.insert(inputs.end(), more_inputs.begin(), more_inputs.end());
  CheckOutputDoesNotOverlapInputs("--out", out_dir, inputs);
  return out_dir;
}

DetectorOptions DetectionRun::WithDevice(DetectorOptions options, const DetectionRunOptions& o) {
  options.device = o.device;
  options.threads = o.threads;
  options.calibration = o.calibration;
  return options;
}

int64_t DetectionRun::DetectFrames(
    const std::function<void(const std::string& id, StereoFrame& frame)>& read, bool overlap) {
  ProgressReporter progress("detect", static_cast<int64_t>(ids.size()), progress_);
  // Two slots: batch k + 1 is read and prepared (slot (k + 1) % 2) while batch k runs.
  std::unique_ptr<Detector::PreparedBatch> slots[2];
  const size_t batch_size = static_cast<size_t>(batch_size_);
  const int num_batches = static_cast<int>((ids.size() + batch_size - 1) / batch_size);
  int64_t objects = 0;
  auto prepare = [&](int k) {
    const size_t begin = static_cast<size_t>(k) * batch_size;
    const size_t n = std::min(ids.size(), begin + batch_size) - begin;
    std::vector<StereoFrame> frames(n);
    ParallelFor(
        n,
        [&](size_t i) {
          StereoFrame& frame = frames[i];
          frame.id = ids[begin + i];
          ScopedStage stage(times_, "read");
          read(frame.id, frame);
        },
        threads_);
    slots[k % 2] = detector.Prepare(frames);
  };
  auto consume = [&](int k) {
    std::vector<DetectResult> results = detector.Run(std::move(slots[k % 2]));
    ScopedStage stage(times_, "write");
    objects += WriteDetectResults(results, out.path(), times_);
    progress.Add(static_cast<int64_t>(results.size()));
  };
  RunTwoStagePipeline(num_batches, overlap, prepare, consume);
  progress.Finish();
  detections_ += objects;
  return objects;
}

DetectSummary DetectionRun::Commit(
    const std::vector<std::pair<std::string, std::string>>& more_inputs,
    const std::string& settings) {
  RunManifest manifest = manifest_;
  manifest.inputs.insert(manifest.inputs.end(), more_inputs.begin(), more_inputs.end());
  const fs::path& calibration = detector.options().calibration;
  if (!calibration.empty()) manifest.inputs.emplace_back("--calibration", calibration.string());
  manifest.settings_json =
      "{\"model_weights_fnv1a64\": \"" + detector.weights_fnv1a64() + "\", " + settings + "}";
  CommitDetectionFolder(out, std::move(manifest), ids, all_ids, shard_, batch_size_);
  DetectSummary summary;
  summary.frames = static_cast<int>(ids.size());
  summary.detections = detections_;
  summary.seconds = timer_.ElapsedSeconds();
  summary.frames_per_second = summary.seconds > 0 ? summary.frames / summary.seconds : 0;
  summary.stage_times = times_.Format();
  return summary;
}

void ReadStereoPairFiles(const FramePaths& paths, const DisparityOptions& disparity,
                         StereoFrame& frame) {
  frame.right = ReadColourImage(paths.image_right);
  CheckStereoPairSize(frame.left, frame.right, paths.image_left, paths.image_right);
  CheckImageFitsMatcher(disparity, frame.left.size(), paths.image_left);
  frame.calib = ReadCalibration(paths.calib);
}

}  // namespace stereodet
