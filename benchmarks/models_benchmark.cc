// models: SSD inference and training throughput, rgb vs rgbh-learned at the same resolution; the
// two-stage detector (models/rpn/) at its default size, rgb vs rgbd (and the widened rgb control).
//   build/benchmarks/models_benchmark --benchmark_counters_tabular=true
// Counters: images_per_s. Threads: STEREODET_BENCH_THREADS (default 2, the target machine's cores).
// The input encoding (EncodeNetworkInput, from a decoded BGR image and a height-code image) is
// measured separately from the network.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <opencv2/core.hpp>
#include <vector>

#include "stereodet/models/box_coder.h"
#include "stereodet/models/input_encoding.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/ssd.h"

namespace stereodet {
namespace {

int BenchThreads() {
  const char* env = std::getenv("STEREODET_BENCH_THREADS");
  return env ? std::atoi(env) : 2;
}

SsdConfig Config(InputEncoding encoding, int width, int height) {
  SsdConfig config;
  config.encoding = encoding;
  config.boxes.input_width = width;
  config.boxes.input_height = height;
  return config;
}

std::vector<PlanarImage> Inputs(const SsdConfig& config, int n) {
  cv::RNG rng(1);
  std::vector<PlanarImage> inputs;
  for (int i = 0; i < n; ++i) {
    cv::Mat bgr(config.InputHeight(), config.InputWidth(), CV_8UC3);
    cv::Mat code(config.InputHeight(), config.InputWidth(), CV_16UC1);
    rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
    rng.fill(code, cv::RNG::UNIFORM, 0, 512);
    inputs.push_back(EncodeNetworkInput(bgr, code, config.encoding));
  }
  return inputs;
}

// Args: encoding, width, height, batch.
void BM_SsdInference(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  const SsdConfig config =
      Config(static_cast<InputEncoding>(state.range(0)), static_cast<int>(state.range(1)),
             static_cast<int>(state.range(2)));
  const SsdModel model(config, 1);
  const auto inputs = Inputs(config, static_cast<int>(state.range(3)));
  for (auto _ : state) benchmark::DoNotOptimize(model.Forward(inputs));
  state.SetLabel(InputEncodingName(config.encoding));
  state.counters["images_per_s"] = benchmark::Counter(
      static_cast<double>(state.iterations() * inputs.size()), benchmark::Counter::kIsRate);
  state.counters["GMAC"] = static_cast<double>(model.MultiplyAccumulates()) * 1e-9;
  state.counters["params"] = static_cast<double>(model.ParameterCount());
}

void BM_SsdEncode(benchmark::State& state) {
  const InputEncoding encoding = static_cast<InputEncoding>(state.range(0));
  const int width = static_cast<int>(state.range(1)), height = static_cast<int>(state.range(2));
  cv::Mat bgr(height, width, CV_8UC3), code(height, width, CV_16UC1);
  cv::RNG rng(2);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  rng.fill(code, cv::RNG::UNIFORM, 0, 512);
  for (auto _ : state) benchmark::DoNotOptimize(EncodeNetworkInput(bgr, code, encoding));
  state.SetLabel(InputEncodingName(encoding));
  state.counters["images_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

// Args: encoding, width, height, batch. One optimizer step per iteration (loss, backward, AdamW).
void BM_SsdTrainStep(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  const SsdConfig config =
      Config(static_cast<InputEncoding>(state.range(0)), static_cast<int>(state.range(1)),
             static_cast<int>(state.range(2)));
  SsdModel model(config, 1);
  SsdTrainer trainer(model);
  const int n = static_cast<int>(state.range(3));
  TrainBatch batch;
  batch.batch_size = n;
  batch.channels = NetworkInputChannels(config.encoding);
  batch.height = config.InputHeight();
  batch.width = config.InputWidth();
  batch.images = StackPlanar(Inputs(config, n), batch.channels, batch.height, batch.width);
  // A few objects per frame, as on KITTI.
  const double w = config.InputWidth(), h = config.InputHeight();
  const std::vector<TargetBox> objects = {{{0.1 * w, 0.4 * h, 0.2 * w, 0.6 * h}, 1},
                                          {{0.5 * w, 0.45 * h, 0.53 * w, 0.6 * h}, 2},
                                          {{0.7 * w, 0.3 * h, 0.95 * w, 0.8 * h}, 1}};
  const MatchResult match = MatchDefaultBoxes(model.default_boxes(), objects, {});
  for (int i = 0; i < n; ++i) {
    batch.labels.insert(batch.labels.end(), match.labels.begin(), match.labels.end());
    batch.deltas.insert(batch.deltas.end(), match.deltas.begin(), match.deltas.end());
  }
  for (auto _ : state) benchmark::DoNotOptimize(trainer.Step(batch, 1e-4));
  state.SetLabel(InputEncodingName(config.encoding));
  state.counters["images_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * n), benchmark::Counter::kIsRate);
}

// --- the two-stage detector at its defaults (640 x 192, trunks of width 32). Args: input (0 rgb, 1
// rgbd), image width, batch.
RpnConfig Rpn(const benchmark::State& state) {
  RpnConfig config;
  config.input = state.range(0) == 1 ? RpnInput::kRgbd : RpnInput::kRgb;
  config.image_width = static_cast<int>(state.range(1));
  return config;
}

std::vector<PlanarImage> RpnInputs(const RpnConfig& config, int n) {
  cv::RNG rng(3);
  std::vector<PlanarImage> inputs;
  for (int i = 0; i < n; ++i) {
    cv::Mat bgr(config.input_height, config.input_width, CV_8UC3);
    cv::Mat depth(config.input_height, config.input_width, CV_16UC1);
    cv::Mat height(config.input_height, config.input_width, CV_16UC1);
    rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
    rng.fill(depth, cv::RNG::UNIFORM, 0, 65536);
    rng.fill(height, cv::RNG::UNIFORM, 0, 512);
    inputs.push_back(EncodeRpnInput(bgr, depth, height, config.input));
  }
  return inputs;
}

void RpnCounters(benchmark::State& state, const RpnModel& model, int n) {
  state.SetLabel(RpnInputName(model.config().input));
  state.counters["images_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * n), benchmark::Counter::kIsRate);
  state.counters["params"] = static_cast<double>(model.ParameterCount());
  state.counters["image_params"] = static_cast<double>(model.ImageBranchParameterCount());
  state.counters["geometry_params"] = static_cast<double>(model.GeometryBranchParameterCount());
}

// Detection: trunks, RPN, 600 -> 100 proposals (NMS), RoIAlign, head, per-class NMS.
void BM_RpnDetect(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  const RpnModel model(Rpn(state), 1);
  const int n = static_cast<int>(state.range(2));
  const auto inputs = RpnInputs(model.config(), n);
  for (auto _ : state) benchmark::DoNotOptimize(model.Detect(inputs));
  RpnCounters(state, model, n);
}

// One optimizer step: forward, anchor and RoI sampling (1000 -> 300 proposals), losses, backward,
// AdamW. Three objects per frame, as on KITTI.
void BM_RpnTrainStep(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  RpnModel model(Rpn(state), 1);
  RpnTrainer trainer(model);
  const int n = static_cast<int>(state.range(2));
  const double w = model.config().input_width, h = model.config().input_height;
  RpnBatch batch;
  batch.inputs = RpnInputs(model.config(), n);
  batch.objects.assign(n, {{{0.1 * w, 0.4 * h, 0.2 * w, 0.6 * h}, 1},
                           {{0.5 * w, 0.45 * h, 0.53 * w, 0.6 * h}, 2},
                           {{0.7 * w, 0.3 * h, 0.95 * w, 0.8 * h}, 1}});
  uint64_t step = 0;
  for (auto _ : state) benchmark::DoNotOptimize(trainer.Step(batch, 1e-4, ++step));
  RpnCounters(state, model, n);
}

constexpr int kRpnRgb = 0;
constexpr int kRpnRgbd = 1;

constexpr int kRgb = static_cast<int>(InputEncoding::kRgb);
constexpr int kLearned = static_cast<int>(InputEncoding::kRgbhLearned);

BENCHMARK(BM_SsdInference)
    ->Args({kRgb, 621, 188, 8})
    ->Args({kLearned, 621, 188, 8})
    ->Args({kRgb, 414, 125, 8})
    ->Args({kLearned, 414, 125, 8})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_SsdEncode)
    ->Args({kRgb, 621, 188})
    ->Args({kLearned, 621, 188})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();
BENCHMARK(BM_SsdTrainStep)
    ->Args({kRgb, 621, 188, 8})
    ->Args({kLearned, 621, 188, 8})
    ->Args({kRgb, 414, 125, 8})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(5.0);
// 39: the widened rgb control, within 1% of the rgbd model's parameter count (docs/models.md).
BENCHMARK(BM_RpnDetect)
    ->Args({kRpnRgb, 32, 4})
    ->Args({kRpnRgbd, 32, 4})
    ->Args({kRpnRgb, 39, 4})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_RpnTrainStep)
    ->Args({kRpnRgb, 32, 4})
    ->Args({kRpnRgbd, 32, 4})
    ->Args({kRpnRgb, 39, 4})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(5.0);

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
