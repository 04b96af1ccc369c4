// Evaluation speed (docs/BENCHMARKS.md, section "eval"):
//  - BM_FullEvaluation/MATCHER/FP: a KITTI-val-sized set (3769 frames, ~18k labels, detections with
//    FP false positives per frame on top of noisy, sometimes duplicated detections of the labels),
//    3 classes x 3 difficulties x 2D/BEV/3D, AP_R40 + AP_R11 + AOS and the operating-point metrics,
//    on 2 threads. MATCHER: 0 kitti, 1 optimal, 2 voc. Counters: labels, detections, peak RSS.
//  - BM_FrameScaling/MATCHER/N: one frame with N labels in a row, each overlapping its neighbours,
//    and N detections overlapping about 7 labels each (tau 0.5): the matcher's per-frame work.
// Run one benchmark per process for a clean peak-RSS figure, e.g.
//   eval_benchmark --benchmark_filter='BM_FullEvaluation/1/2/'
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <map>
#include <utility>
#include <vector>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/voc_matcher_internal.h"

namespace stereodet {
namespace {

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
}

const std::vector<EvalFrame>& ValSizedSet(int fp_per_frame) {
  static std::map<int, std::vector<EvalFrame>> cache;
  auto it = cache.find(fp_per_frame);
  if (it == cache.end()) {
    RandomFramesOptions o;
    o.num_frames = 3769;
    o.labels_per_frame = 4.8;
    o.false_positives_per_frame = fp_per_frame;
    o.score_decimals = 4;
    o.seed = 2024;
    it = cache.emplace(fp_per_frame, RandomFrames(o)).first;
  }
  return it->second;
}

void BM_FullEvaluation(benchmark::State& state) {
  const std::vector<EvalFrame>& frames = ValSizedSet(static_cast<int>(state.range(1)));
  EvalOptions options;
  options.matcher = static_cast<Matcher>(state.range(0));
  options.num_threads = 2;
  int64_t labels = 0, detections = 0;
  for (const EvalFrame& f : frames) {
    labels += static_cast<int64_t>(f.labels.size());
    detections += static_cast<int64_t>(f.detections.size());
  }
  double ap = 0;
  for (auto _ : state) {
    const EvalResult r = Evaluate(frames, options);
    ap = r.Find("Car", OverlapKind::k3D, Difficulty::kModerate)->ap_r40;
    benchmark::DoNotOptimize(ap);
  }
  state.SetLabel(MatcherName(options.matcher));
  state.counters["frames"] = static_cast<double>(frames.size());
  state.counters["labels"] = static_cast<double>(labels);
  state.counters["detections"] = static_cast<double>(detections);
  state.counters["car_3d_mod_ap_r40"] = ap;
  state.counters["peak_rss_mb"] = PeakRssMb();
}
BENCHMARK(BM_FullEvaluation)
    ->ArgsProduct({{0, 1, 2}, {2, 22}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

EvalFrame ScalingFrame(int n) {
  EvalFrame f;
  for (int i = 0; i < n; ++i) {
    Object label;
    label.type = "Pedestrian";
    label.box = Box2D{10.0 * i, 100, 10.0 * i + 100, 200};
    f.labels.push_back(label);
  }
  for (int i = 0; i < n; ++i) {
    Object det;
    det.type = "Pedestrian";
    const double shift = (i % 3 - 1) * 4.0;
    det.box = Box2D{10.0 * i + shift, 100, 10.0 * i + 100 + shift, 200};
    det.score = 1.0 - static_cast<double>((i * 7919) % n) / n;
    f.detections.push_back(det);
  }
  return f;
}

void BM_FrameScaling(benchmark::State& state) {
  const Matcher matcher = static_cast<Matcher>(state.range(0));
  const int n = static_cast<int>(state.range(1));
  const EvalFrame frame = ScalingFrame(n);
  const ClassFrame cf = PrepareClassFrame(frame, KittiClassSpec("Pedestrian"), OverlapKind::k2D);
  int64_t tp = 0;
  for (auto _ : state) {
    std::vector<CurveEvent> events;
    if (matcher == Matcher::kKitti) {
      const std::vector<double> scores = KittiCollectTpScores(cf, Difficulty::kModerate).scores;
      const std::vector<double> thresholds = KittiThresholds(scores, n);
      const std::vector<KittiCounts> counts =
          KittiAddFrameCounts(cf, Difficulty::kModerate, thresholds);
      benchmark::DoNotOptimize(counts.data());
    } else if (matcher == Matcher::kOptimal) {
      events = OptimalFrameEvents(cf, Difficulty::kModerate, std::move(events));
    } else {
      events = VocFrameEvents(cf, Difficulty::kModerate, std::move(events));
    }
    tp = Associate(matcher, cf, Difficulty::kModerate, 0.0).CountDets(Outcome::kTp);
    benchmark::DoNotOptimize(tp);
  }
  state.SetLabel(MatcherName(matcher));
  state.counters["edges"] = static_cast<double>(cf.edge_det.size());
  state.counters["tp"] = static_cast<double>(tp);
  state.SetComplexityN(n);
}
BENCHMARK(BM_FrameScaling)
    ->ArgsProduct({{0, 1, 2}, {10, 100, 1000, 3000}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
