// Bootstrap speed (docs/BENCHMARKS.md, section "eval bootstrap"), on the KITTI-val-sized random set
// of eval_benchmark (3769 frames, ~18k labels, 2 false positives per frame), 3 classes x 3
// difficulties x 2D/BEV/3D = 27 cells, 2 threads:
//  - BM_Bootstrap/MATCHER/R: Bootstrap() with R resamples (per-frame preparation once, then R
//    resamples of all 27 cells). The time per resample is (t(R=101) - t(R=1)) / 100.
//  - BM_BruteForceResample/MATCHER: what one resample costs without the per-frame statistics:
//    materialise the resampled frame list and Evaluate() it (the test's reference).
//  - BM_Bootstrap/MATCHER/R/1: the same with --breakdown distance=0,30,50,inf (3 bins per cell:
//    81 bins beside the 27 cells get intervals too).
// MATCHER: 0 kitti, 1 optimal.
//   bootstrap_benchmark --benchmark_min_time=1
#include <benchmark/benchmark.h>

#include <vector>

#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"

namespace stereodet {
namespace {

const std::vector<EvalFrame>& ValSizedSet() {
  static const std::vector<EvalFrame> frames = [] {
    RandomFramesOptions o;
    o.num_frames = 3769;
    o.labels_per_frame = 4.8;
    o.false_positives_per_frame = 2;
    o.score_decimals = 4;
    o.seed = 2024;
    return RandomFrames(o);
  }();
  return frames;
}

void BM_Bootstrap(benchmark::State& state) {
  const std::vector<EvalFrame>& frames = ValSizedSet();
  EvalOptions eval;
  eval.matcher = static_cast<Matcher>(state.range(0));
  eval.num_threads = 2;
  if (state.range(2) != 0) eval.breakdowns = {ParseBreakdown("distance=0,30,50,inf")};
  BootstrapOptions options;
  options.num_resamples = static_cast<int>(state.range(1));
  options.num_threads = 2;
  double lower = 0;
  for (auto _ : state) {
    const BootstrapResult r = Bootstrap(frames, eval, options);
    lower =
        r.Find("Car", OverlapKind::k3D, Difficulty::kModerate)->Get(BootstrapMetric::kApR40).lower;
    benchmark::DoNotOptimize(lower);
  }
  state.SetLabel(MatcherName(eval.matcher));
  state.counters["resamples"] = static_cast<double>(options.num_resamples);
  state.counters["breakdown_bins"] = state.range(2) != 0 ? 3 : 0;
  state.counters["car_3d_mod_ap_r40_lower"] = lower;
}
BENCHMARK(BM_Bootstrap)
    ->ArgsProduct({{0, 1}, {1, 101}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_BruteForceResample(benchmark::State& state) {
  const std::vector<EvalFrame>& frames = ValSizedSet();
  EvalOptions eval;
  eval.matcher = static_cast<Matcher>(state.range(0));
  eval.num_threads = 2;
  const std::vector<int32_t> counts =
      BootstrapFrameCounts(static_cast<int64_t>(frames.size()), 1, 0);
  for (auto _ : state) {
    std::vector<EvalFrame> resampled;
    resampled.reserve(frames.size());
    for (size_t f = 0; f < frames.size(); ++f) {
      for (int32_t k = 0; k < counts[f]; ++k) resampled.push_back(frames[f]);
    }
    const EvalResult r = Evaluate(resampled, eval);
    benchmark::DoNotOptimize(r.results.size());
  }
  state.SetLabel(MatcherName(eval.matcher));
}
BENCHMARK(BM_BruteForceResample)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
