// Parsing speed of the KITTI readers on a KITTI-val-sized set (issue 2's target: <= 50 ms on one
// core for 3769 frames, about 45k label and detection lines).
//
// The set is generated in memory with KITTI's number style (two decimals, DontCare sentinels) and
// KITTI val's class mix: about 5.3 label lines and 6.6 detection lines a frame. Figures:
//   BM_ParseLabelsAndDetections  the target: all label and detection texts, in memory, one thread
//   BM_ParseCalibrations         the 3769 calib texts, in memory
//   BM_ReadLabelsAndDetectionsFromFiles  the same from files in a temp folder (warm page cache)
#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/atomic_file.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 3769;  // KITTI val (Chen et al.'s split)

struct Set {
  std::vector<std::string> labels, detections, calibs;
  size_t label_lines = 0, detection_lines = 0;
};

double Two(double v) { return std::round(v * 100.0) / 100.0; }

Object RandomObject(std::mt19937& rng, bool detection) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Object o;
  const double r = u(rng);
  if (!detection && r < 0.25) {
    o.type = "DontCare";
    o.truncated = -1;
    o.occluded = -1;
    o.box = {Two(100 + 1000 * u(rng)), Two(150 + 50 * u(rng)), 0, 0};
    o.box.right = Two(o.box.left + 10 + 80 * u(rng));
    o.box.bottom = Two(o.box.top + 5 + 40 * u(rng));
    o.SetNot3DEstimated();
    return o;
  }
  o.type = r < 0.8 ? "Car" : r < 0.9 ? "Pedestrian" : r < 0.95 ? "Cyclist" : "Van";
  o.truncated = detection ? -1 : Two(u(rng) < 0.8 ? 0.0 : u(rng));
  o.occluded = detection ? -1 : static_cast<int>(4 * u(rng));
  o.alpha = Two(-3.14 + 6.28 * u(rng));
  o.box.left = Two(1200 * u(rng));
  o.box.top = Two(140 + 60 * u(rng));
  o.box.right = Two(o.box.left + 20 + 200 * u(rng));
  o.box.bottom = Two(o.box.top + 20 + 150 * u(rng));
  o.box3d.h = Two(1.4 + 0.3 * u(rng));
  o.box3d.w = Two(1.5 + 0.3 * u(rng));
  o.box3d.l = Two(3.5 + 1.0 * u(rng));
  o.box3d.location = {Two(-20 + 40 * u(rng)), Two(1.5 + 0.5 * u(rng)), Two(5 + 65 * u(rng))};
  o.box3d.rotation_y = Two(-3.14 + 6.28 * u(rng));
  if (detection) o.score = Two(u(rng));
  return o;
}

const Set& GetSet() {
  static const Set set = [] {
    Set s;
    std::mt19937 rng(2024);
    std::poisson_distribution<int> label_count(5.3), detection_count(6.6);
    const std::string calib = FormatCalibration(KittiLikeCalibration());
    for (int f = 0; f < kFrames; ++f) {
      std::vector<Object> labels(label_count(rng)), detections(detection_count(rng));
      for (Object& o : labels) o = RandomObject(rng, false);
      for (Object& o : detections) o = RandomObject(rng, true);
      s.labels.push_back(FormatObjects(labels));
      s.detections.push_back(FormatObjects(detections));
      s.calibs.push_back(calib);
      s.label_lines += labels.size();
      s.detection_lines += detections.size();
    }
    return s;
  }();
  return set;
}

void SetCounters(benchmark::State& state, size_t lines) {
  state.counters["lines"] = static_cast<double>(lines);
  state.counters["lines/s"] =
      benchmark::Counter(static_cast<double>(lines), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["frames"] = kFrames;
}

void BM_ParseLabelsAndDetections(benchmark::State& state) {
  const Set& set = GetSet();
  ObjectParseOptions label_options, detection_options;
  detection_options.kind = ObjectFileKind::kDetection;
  const std::string source = "label_2/000000.txt";
  for (auto _ : state) {
    size_t objects = 0;
    for (int f = 0; f < kFrames; ++f) {
      objects += ParseObjects(set.labels[f], source, label_options).objects.size();
      objects += ParseObjects(set.detections[f], source, detection_options).objects.size();
    }
    benchmark::DoNotOptimize(objects);
  }
  SetCounters(state, set.label_lines + set.detection_lines);
}
BENCHMARK(BM_ParseLabelsAndDetections)->Unit(benchmark::kMillisecond);

void BM_ParseCalibrations(benchmark::State& state) {
  const Set& set = GetSet();
  const std::string source = "calib/000000.txt";
  for (auto _ : state) {
    double sum = 0;
    for (int f = 0; f < kFrames; ++f) sum += ParseCalibration(set.calibs[f], source).FocalPx();
    benchmark::DoNotOptimize(sum);
  }
  SetCounters(state, static_cast<size_t>(kFrames) * 8);
}
BENCHMARK(BM_ParseCalibrations)->Unit(benchmark::kMillisecond);

void BM_FormatLabelsAndDetections(benchmark::State& state) {
  const Set& set = GetSet();
  std::vector<std::vector<Object>> parsed;
  ObjectParseOptions any;
  any.kind = ObjectFileKind::kAny;
  for (int f = 0; f < kFrames; ++f) {
    parsed.push_back(ParseObjects(set.labels[f], "x", any).objects);
    parsed.push_back(ParseObjects(set.detections[f], "x", any).objects);
  }
  for (auto _ : state) {
    size_t bytes = 0;
    for (const auto& objects : parsed) bytes += FormatObjects(objects).size();
    benchmark::DoNotOptimize(bytes);
  }
  SetCounters(state, set.label_lines + set.detection_lines);
}
BENCHMARK(BM_FormatLabelsAndDetections)->Unit(benchmark::kMillisecond);

// Files in a temp folder: label_2/ and det/ of kFrames frames each.
const fs::path& FilesDir() {
  static const fs::path dir = [] {
    const fs::path d =
        fs::temp_directory_path() / fmt::format("stereodet_kitti_bench_{}", ::getpid());
    const Set& set = GetSet();
    for (int f = 0; f < kFrames; ++f) {
      WriteFileAtomically(d / "label_2" / (FrameId(f) + ".txt"), set.labels[f]);
      WriteFileAtomically(d / "det" / (FrameId(f) + ".txt"), set.detections[f]);
    }
    std::atexit([] { fs::remove_all(FilesDir()); });
    return d;
  }();
  return dir;
}

void BM_ReadLabelsAndDetectionsFromFiles(benchmark::State& state) {
  const fs::path& dir = FilesDir();
  std::vector<fs::path> labels, detections;
  for (int f = 0; f < kFrames; ++f) {
    labels.push_back(dir / "label_2" / (FrameId(f) + ".txt"));
    detections.push_back(dir / "det" / (FrameId(f) + ".txt"));
  }
  ObjectParseOptions label_options, detection_options;
  detection_options.kind = ObjectFileKind::kDetection;
  for (auto _ : state) {
    size_t objects = 0;
    for (int f = 0; f < kFrames; ++f) {
      objects += ReadObjects(labels[f], label_options).objects.size();
      objects += ReadObjects(detections[f], detection_options).objects.size();
    }
    benchmark::DoNotOptimize(objects);
  }
  SetCounters(state, GetSet().label_lines + GetSet().detection_lines);
}
BENCHMARK(BM_ReadLabelsAndDetectionsFromFiles)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
