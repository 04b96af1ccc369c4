#include "stereodet/realtime/latency.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace stereodet {
namespace {

TEST(LatencyTest, NearestRankQuantileByHand) {
  std::vector<double> v = {5, 1, 4, 2, 3};  // sorted: 1 2 3 4 5
  EXPECT_EQ(NearestRankQuantile(v, 0.0), 1);
  EXPECT_EQ(NearestRankQuantile(v, 0.2), 1);   // ceil(1.0) = 1st
  EXPECT_EQ(NearestRankQuantile(v, 0.21), 2);  // ceil(1.05) = 2nd
  EXPECT_EQ(NearestRankQuantile(v, 0.5), 3);   // ceil(2.5) = 3rd
  EXPECT_EQ(NearestRankQuantile(v, 0.99), 5);
  EXPECT_EQ(NearestRankQuantile(v, 1.0), 5);
  std::vector<double> none;
  EXPECT_EQ(NearestRankQuantile(none, 0.5), 0.0);
}

// Against the definition, on random samples: the smallest value with at least ceil(q n) values at
// or below it.
TEST(LatencyTest, NearestRankQuantileMatchesItsDefinition) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 40);
    std::vector<double> v(n);
    for (double& x : v) x = static_cast<double>(rng() % 20);  // ties on purpose
    const double q = (rng() % 1001) / 1000.0;
    std::vector<double> copy = v;
    const double got = NearestRankQuantile(copy, q);
    const double need = std::max(1.0, std::ceil(q * n));
    double best = 1e300;
    for (double candidate : v) {
      if (std::count_if(v.begin(), v.end(), [&](double x) { return x <= candidate; }) >= need) {
        best = std::min(best, candidate);
      }
    }
    EXPECT_EQ(got, best) << "n " << n << " q " << q;
  }
}

TEST(LatencyTest, RecorderKeepsTheWarmupApart) {
  LatencyRecorder recorder(/*warmup_frames=*/2);
  recorder.Record({{"network", 100}, {"end_to_end", 200}});  // warm-up
  recorder.Record({{"network", 90}});                        // warm-up
  for (int i = 1; i <= 10; ++i) recorder.Record({{"network", double(i)}, {"end_to_end", 10.0 * i}});
  EXPECT_EQ(recorder.frames(), 12);
  // First seen in the first frame, in name order (a map).
  EXPECT_EQ(recorder.stages(), (std::vector<std::string>{"end_to_end", "network"}));
  const LatencySummary network = recorder.Summary("network");
  EXPECT_EQ(network.frames, 10);
  EXPECT_EQ(network.p50_ms, 5);
  EXPECT_EQ(network.p90_ms, 9);
  EXPECT_EQ(network.p99_ms, 10);
  EXPECT_EQ(network.max_ms, 10);
  EXPECT_DOUBLE_EQ(network.mean_ms, 5.5);
  const LatencySummary warmup = recorder.Summary("network", /*warmup=*/true);
  EXPECT_EQ(warmup.frames, 2);
  EXPECT_EQ(warmup.max_ms, 100);
  EXPECT_EQ(recorder.Summary("end_to_end", true).frames, 1);
  EXPECT_EQ(recorder.Summary("stereo").frames, 0);
}

}  // namespace
}  // namespace stereodet
