// Speed of the IoU functions on one core (issue 2's target: BEV rotated IoU >= 5 M pairs/s).
//
// Pairs are realistic: a KITTI-sized car (l 3.9, w 1.6, h 1.5 m, jittered) anywhere 5-70 m ahead
// at any heading, and a detection of it offset by ~0.5 m, turned by ~0.2 rad and resized by ~5%,
// so almost every pair overlaps and takes the full rotated-rectangle clipping path. A second set of
// pairs draws both boxes independently over the scene, the usual case when a frame's detections
// are matched against all its labels, where most pairs are rejected early.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "stereodet/geometry/iou.h"

namespace stereodet {
namespace {

constexpr int kPairs = 4096;

Box3D RandomCar(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  Box3D box;
  box.l = 3.9 + 0.3 * n(rng);
  box.w = 1.6 + 0.1 * n(rng);
  box.h = 1.5 + 0.1 * n(rng);
  box.location = {-20 + 40 * u(rng), 1.6 + 0.1 * n(rng), 5 + 65 * u(rng)};
  box.rotation_y = -M_PI + 2 * M_PI * u(rng);
  return box;
}

struct Pairs {
  std::vector<Box3D> a, b;
};

const Pairs& OverlappingPairs() {
  static const Pairs pairs = [] {
    Pairs p;
    std::mt19937 rng(1);
    std::normal_distribution<double> n(0.0, 1.0);
    for (int i = 0; i < kPairs; ++i) {
      const Box3D label = RandomCar(rng);
      Box3D det = label;
      det.location += Eigen::Vector3d(0.5 * n(rng), 0.1 * n(rng), 0.5 * n(rng));
      det.rotation_y += 0.2 * n(rng);
      det.l *= 1 + 0.05 * n(rng);
      det.w *= 1 + 0.05 * n(rng);
      det.h *= 1 + 0.05 * n(rng);
      p.a.push_back(label);
      p.b.push_back(det);
    }
    return p;
  }();
  return pairs;
}

const Pairs& ScenePairs() {
  static const Pairs pairs = [] {
    Pairs p;
    std::mt19937 rng(2);
    for (int i = 0; i < kPairs; ++i) {
      p.a.push_back(RandomCar(rng));
      p.b.push_back(RandomCar(rng));
    }
    return p;
  }();
  return pairs;
}

template <double (*Iou)(const Box3D&, const Box3D&)>
void RunPairs(benchmark::State& state, const Pairs& pairs) {
  double overlapping = 0;
  for (int i = 0; i < kPairs; ++i) overlapping += Iou(pairs.a[i], pairs.b[i]) > 0;
  for (auto _ : state) {
    double sum = 0;
    for (int i = 0; i < kPairs; ++i) sum += Iou(pairs.a[i], pairs.b[i]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kPairs);
  state.counters["overlapping"] = overlapping / kPairs;
}

void BM_BevIouOverlappingCars(benchmark::State& state) {
  RunPairs<BevIou>(state, OverlappingPairs());
}
BENCHMARK(BM_BevIouOverlappingCars);

void BM_BevIouScenePairs(benchmark::State& state) { RunPairs<BevIou>(state, ScenePairs()); }
BENCHMARK(BM_BevIouScenePairs);

void BM_Iou3DOverlappingCars(benchmark::State& state) {
  RunPairs<Iou3D>(state, OverlappingPairs());
}
BENCHMARK(BM_Iou3DOverlappingCars);

void BM_Iou2D(benchmark::State& state) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Box2D> a, b;
  for (int i = 0; i < kPairs; ++i) {
    const double left = 1000 * u(rng), top = 150 + 50 * u(rng);
    a.push_back({left, top, left + 50 + 100 * u(rng), top + 40 + 80 * u(rng)});
    const double dx = 20 * (u(rng) - 0.5), dy = 10 * (u(rng) - 0.5);
    b.push_back({a.back().left + dx, a.back().top + dy, a.back().right + dx, a.back().bottom + dy});
  }
  for (auto _ : state) {
    double sum = 0;
    for (int i = 0; i < kPairs; ++i) sum += Iou2D(a[i], b[i]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * kPairs);
}
BENCHMARK(BM_Iou2D);

}  // namespace
}  // namespace stereodet

BENCHMARK_MAIN();
