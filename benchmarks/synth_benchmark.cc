// Speed of `stereodet synth` (issue 5's target: >= 5 frames/s at 1242 x 375, both cameras and the
// LiDAR, on 2 cores). Figures go to docs/BENCHMARKS.md, section "synth".
#include <benchmark/benchmark.h>

#include <filesystem>

#include "stereodet/synth/generator.h"
#include "stereodet/util/malloc_tuning.h"

namespace stereodet {
namespace {

// One whole frame on one thread: scene, both cameras, disparity, labels, LiDAR.
void BM_GenerateFrame(benchmark::State& state) {
  const SynthOptions options;
  int index = 0;
  for (auto _ : state) {
    SynthFrame frame = GenerateFrame(options, 1, index++ % 16);
    benchmark::DoNotOptimize(frame.labels.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GenerateFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_RenderCamera(benchmark::State& state) {
  const SynthOptions options;
  const Scene scene = SampleScene(options.scene, 42);
  const Calibration calib = SynthCalibration(1242, 375);
  RenderRequest request;
  for (auto _ : state) {
    CameraRender render = RenderCamera(scene, calib, request, options.render);
    benchmark::DoNotOptimize(render.image.data);
  }
}
BENCHMARK(BM_RenderCamera)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Lidar(benchmark::State& state) {
  const SynthOptions options;
  const Scene scene = SampleScene(options.scene, 42);
  const Calibration calib = SynthCalibration(1242, 375);
  for (auto _ : state) {
    std::vector<VeloPoint> scan = SimulateLidar(scene, calib, options.lidar_options, 1);
    benchmark::DoNotOptimize(scan.data());
  }
}
BENCHMARK(BM_Lidar)->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole command on `threads` threads, files written: frames/s is items_per_second.
void BM_Dataset(benchmark::State& state) {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / "stereodet_synth_benchmark";
  constexpr int kFrames = 16;
  for (auto _ : state) {
    state.PauseTiming();
    std::filesystem::remove_all(out);
    state.ResumeTiming();
    DatasetOptions options;
    options.out = out;
    options.frames = kFrames;
    options.seed = 1;
    options.threads = static_cast<int>(state.range(0));
    options.progress.stream = nullptr;
    GenerateDataset(options);
  }
  std::filesystem::remove_all(out);
  state.SetItemsProcessed(state.iterations() * kFrames);
}
BENCHMARK(BM_Dataset)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
}  // namespace stereodet

// BENCHMARK_MAIN, under the stereodet executables' allocator policy (util/malloc_tuning.h), so that
// the figures are the ones `stereodet synth` has.
int main(int argc, char** argv) {
  stereodet::KeepLargeBuffersInHeap();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
