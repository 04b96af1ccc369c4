// Latency statistics of a stream: per stage and end to end, the frames, p50 / p90 / p99 / max in
// ms, with the first (warm-up) frames kept apart, since LibTorch's first calls allocate and pick
// kernels and would otherwise dominate the tail.
#ifndef STEREODET_REALTIME_LATENCY_H_
#define STEREODET_REALTIME_LATENCY_H_

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace stereodet {

// The order statistics of one stage's samples.
struct LatencySummary {
  int64_t frames = 0;
  double p50_ms = 0, p90_ms = 0, p99_ms = 0, max_ms = 0, mean_ms = 0;
};

// The q-quantile (q in [0, 1]) of `values` by the nearest-rank method: the smallest value with at
// least ceil(q n) values at or below it (q = 0: the minimum). 0 for no values. `values` is sorted
// in place.
double NearestRankQuantile(std::vector<double>& values, double q);

// Samples in ms per stage name, in two groups: the first `warmup_frames` frames, and the rest.
// Not thread-safe: one thread records (the stream's writer).
class LatencyRecorder {
 public:
  explicit LatencyRecorder(int warmup_frames = 0) : warmup_frames_(warmup_frames) {}

  // One frame's samples (stage name -> ms). Frames are counted in the order they are recorded.
  void Record(const std::map<std::string, double>& stage_ms);

  int64_t frames() const { return frames_; }
  // The stages seen, in first-seen order (a frame's in name order).
  const std::vector<std::string>& stages() const { return order_; }
  // `stage`'s summary over the frames after the warm-up (warmup = false) or of the warm-up.
  LatencySummary Summary(const std::string& stage, bool warmup = false) const;

 private:
  int warmup_frames_;
  int64_t frames_ = 0;
  std::vector<std::string> order_;
  std::map<std::string, std::vector<double>> steady_, warmup_;
};

}  // namespace stereodet

#endif  // STEREODET_REALTIME_LATENCY_H_
