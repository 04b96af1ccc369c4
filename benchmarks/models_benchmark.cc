// models: one frame of each committed model through Detector (BM_DetectorFrame); SSD inference
// and training throughput, rgb vs rgbh-learned at the same resolution; the
// 3D detector's (det3d) training step, detection and sample building at its grid / width options;
// the two-stage detector (models/rpn/) at its default size, rgb vs rgbd (and the widened rgb
// control).
//   build/benchmarks/models_benchmark --benchmark_counters_tabular=true
// Counters: images_per_s, frames_per_s. Threads: STEREODET_BENCH_THREADS (default 2, the target
// machine's cores). The input encoding (EncodeNetworkInput, from a decoded BGR image and a
// height-code image) is measured separately from the network.
#include <arpa/inet.h>
#include <benchmark/benchmark.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/det3d/gt_database.h"
#include "stereodet/models/detector.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/ssd/input_encoding.h"
#include "stereodet/models/ssd/ssd_model.h"

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

// --- det3d ---------------------------------------------------------------------------------------

// A street-like frame in the velodyne frame: `ground_points` on a plane 1.73 m down over the
// default grid's 48 x 48 m (denser near the sensor, as a scan is) and six cars of 400 points each.
Det3dFrame Det3dBenchFrame(int ground_points) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Det3dFrame frame;
  for (int i = 0; i < 6; ++i) {
    frame.boxes.push_back({.x = 6.0 + 6.5 * i,
                           .y = (i % 2 ? 3.5 : -3.0) + u(rng),
                           .z = -0.95,
                           .l = 3.9,
                           .w = 1.6,
                           .h = 1.56,
                           .yaw = 0.3 * i,
                           .label = 0});
  }
  for (int i = 0; i < ground_points; ++i) {
    const double range = 2.0 + 46.0 * u(rng) * u(rng), angle = (u(rng) - 0.5) * 1.4;
    frame.points.push_back({static_cast<float>(range * std::cos(angle)),
                            static_cast<float>(range * std::sin(angle)), -1.73f, 0.2f});
  }
  for (const LidarBox& b : frame.boxes) {
    for (int n = 0; n < 400; ++n) {
      const double along = (u(rng) - 0.5) * b.l, across = (u(rng) - 0.5) * b.w;
      frame.points.push_back(
          {static_cast<float>(b.x + std::cos(b.yaw) * along - std::sin(b.yaw) * across),
           static_cast<float>(b.y + std::sin(b.yaw) * along + std::cos(b.yaw) * across),
           static_cast<float>(b.z + (u(rng) - 0.5) * b.h), 0.7f});
    }
  }
  return frame;
}

// Args: base channels (--width), pillar size in cm (--pillar), ground points.
Det3dConfig Det3dBenchConfig(const benchmark::State& state) {
  Det3dConfig config;
  config.base_channels = static_cast<int>(state.range(0));
  config.grid.pillar_m = state.range(1) / 100.0;
  return config;
}

void Det3dLabel(benchmark::State& state, const Det3dConfig& config, const Det3dModel& model) {
  char label[64];
  std::snprintf(label, sizeof(label), "w%d p%.2f %dx%d", config.base_channels, config.grid.pillar_m,
                config.grid.Rows(), config.grid.Cols());
  state.SetLabel(label);
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["params"] = static_cast<double>(model.ParameterCount());
}

// One optimizer step at batch 1 (forward with the auxiliary network, losses, backward, AdamW), on
// a prepared sample: what `train det3d` does per frame besides building the sample.
void BM_Det3dTrainStep(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  const Det3dConfig config = Det3dBenchConfig(state);
  Det3dModel model(config, 1);
  Det3dTrainer trainer(model);
  const std::vector<Det3dSample> batch = {MakeDet3dSample(
      Det3dBenchFrame(static_cast<int>(state.range(2))), config, model.anchors(), true)};
  for (auto _ : state) benchmark::DoNotOptimize(trainer.Step(batch, 1e-3));
  Det3dLabel(state, config, model);
}

// Detection of one frame from its sample (network, decoding, rotated NMS).
void BM_Det3dDetect(benchmark::State& state) {
  SetTorchThreads(BenchThreads());
  const Det3dConfig config = Det3dBenchConfig(state);
  const Det3dModel model(config, 1);
  const std::vector<Det3dSample> samples = {MakeDet3dSample(
      Det3dBenchFrame(static_cast<int>(state.range(2))), config, model.anchors(), false)};
  for (auto _ : state) benchmark::DoNotOptimize(model.Detect(samples));
  Det3dLabel(state, config, model);
}

// The training sample of a frame (GT sampling from a 40-object database, augmentation, pillars,
// anchor and auxiliary targets), single-threaded: the data side of a training step.
void BM_Det3dSample(benchmark::State& state) {
  const Det3dConfig config = Det3dBenchConfig(state);
  const Det3dModel model(config, 1);
  const Det3dFrame frame = Det3dBenchFrame(static_cast<int>(state.range(2)));
  std::vector<Det3dFrame> others;
  for (int k = 0; k < 7; ++k) {
    Det3dFrame other = frame;
    for (LidarBox& b : other.boxes) b.y += 2.0 * (k + 1);
    for (VeloPoint& p : other.points) p.y += 2.0f * (k + 1);
    others.push_back(std::move(other));
  }
  const GtDatabase database = BuildGtDatabase(others, 1, PointSource::kLidar, {});
  uint64_t seed = 0;
  for (auto _ : state) {
    ++seed;  // before the call: its arguments' order of evaluation is unspecified
    const Det3dFrame augmented =
        AugmentFrame(SampleGtObjects(frame, database, {}, seed).frame, {}, seed);
    benchmark::DoNotOptimize(MakeDet3dSample(augmented, config, model.anchors(), true));
  }
  Det3dLabel(state, config, model);
}

// One frame through Detector, the interface every command runs (models/detector.h): a committed
// model of each family on a frame held in memory (nothing read or decoded in the loop), 1242 x 375
// px noise with a textured box, the right image shifted 24 px (a disparity to match), KITTI's
// calibration, and for the 3D models the synthetic scan above (LiDAR) or the pair (stereo).
// Counters: frames_per_s, and each stage's mean ms (stereo, encode, network, decode).
constexpr const char* kDetectorModels[] = {"ssd-rgb",  "ssd-rgbh-learned", "rpn-rgb",
                                           "rpn-rgbd", "det3d-lidar",      "det3d-stereo"};

void BM_DetectorFrame(benchmark::State& state) {
  const std::filesystem::path source = STEREODET_SOURCE_DIR;
  const std::string name = kDetectorModels[state.range(0)];
  DetectorOptions options;
  options.threads = BenchThreads();
  Detector detector = Detector::Open(source / "models" / name, options);
  cv::RNG rng(2);
  cv::Mat wide(375, 1242 + 24, CV_8UC3);
  rng.fill(wide, cv::RNG::UNIFORM, 30, 120);
  cv::rectangle(wide, cv::Rect(500, 160, 220, 110), cv::Scalar(210, 200, 190), cv::FILLED);
  StereoFrame frame;
  frame.id = "bench";
  frame.left = wide(cv::Rect(24, 0, 1242, 375)).clone();
  frame.right = wide(cv::Rect(0, 0, 1242, 375)).clone();
  frame.calib = ReadCalibration(source / "tests/data/kitti_mini/training/calib/000000.txt");
  if (detector.needs().points) frame.points = Det3dBenchFrame(20000).points;
  DetectStageTimes sum;
  for (auto _ : state) {
    const DetectResult result = detector.Detect(frame);
    sum.stereo_s += result.times.stereo_s;
    sum.encode_s += result.times.encode_s;
    sum.network_s += result.times.network_s;
    sum.decode_s += result.times.decode_s;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["frames_per_s"] = benchmark::Counter(n, benchmark::Counter::kIsRate);
  state.counters["stereo_ms"] = 1e3 * sum.stereo_s / n;
  state.counters["encode_ms"] = 1e3 * sum.encode_s / n;
  state.counters["network_ms"] = 1e3 * sum.network_s / n;
  state.counters["decode_ms"] = 1e3 * sum.decode_s / n;
  state.SetLabel(name);
}

BENCHMARK(BM_DetectorFrame)
    ->DenseRange(0, 5)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_Det3dTrainStep)
    ->Args({32, 40, 20000})
    ->Args({32, 40, 160000})
    ->Args({16, 40, 20000})
    ->Args({16, 50, 20000})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_Det3dDetect)
    ->Args({32, 40, 20000})
    ->Args({32, 40, 160000})
    ->Args({16, 40, 20000})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);
BENCHMARK(BM_Det3dSample)
    ->Args({32, 40, 20000})
    ->Args({32, 40, 160000})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

// One all-reduce of a training group of 2 ranks on the loopback (models/distributed.h): this
// thread is rank 0, a second thread rank 1 making the same calls. range(0) doubles: 129 is a
// synchronized batch norm of 64 channels (sums, squared sums, count), 232766 the det3d network's
// float gradients (465,532 parameters, 1.86 MB). What the scaling model of docs/BENCHMARKS.md
// ("train --world-size") reads: the latency of a small collective and the bandwidth of a large.
void BM_GroupAllReduce(benchmark::State& state) {
  const int64_t doubles = state.range(0);
  const int64_t iterations = static_cast<int64_t>(state.max_iterations);
  int port = 0;
  {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address));
    socklen_t length = sizeof(address);
    getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
    port = ntohs(address.sin_port);
    close(fd);
  }
  DistributedOptions options;
  options.world_size = 2;
  options.rendezvous = "tcp://127.0.0.1:" + std::to_string(port);
  std::thread peer([&] {
    DistributedOptions o = options;
    o.rank = 1;
    const std::unique_ptr<TrainingGroup> group = TrainingGroup::Connect(o);
    std::vector<double> v(doubles, 1.0);
    for (int64_t i = 0; i < iterations; ++i) group->AllReduceSum(v);
  });
  const std::unique_ptr<TrainingGroup> group = TrainingGroup::Connect(options);
  std::vector<double> v(doubles, 1.0);
  for (auto _ : state) group->AllReduceSum(v);
  peer.join();
  state.SetBytesProcessed(state.iterations() * doubles * static_cast<int64_t>(sizeof(double)));
}

BENCHMARK(BM_GroupAllReduce)
    ->Arg(129)
    ->Arg(232766)
    ->Iterations(400)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
