#include "stereodet/realtime/latency.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace stereodet {

double NearestRankQuantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double n = static_cast<double>(values.size());
  const size_t rank = static_cast<size_t>(std::max(1.0, std::ceil(std::clamp(q, 0.0, 1.0) * n)));
  return values[std::min(rank, values.size()) - 1];
}

void LatencyRecorder::Record(const std::map<std::string, double>& stage_ms) {
  const bool warmup = frames_ < warmup_frames_;
  for (const auto& [stage, ms] : stage_ms) {
    if (std::find(order_.begin(), order_.end(), stage) == order_.end()) order_.push_back(stage);
    (warmup ? warmup_ : steady_)[stage].push_back(ms);
  }
  ++frames_;
}

LatencySummary LatencyRecorder::Summary(const std::string& stage, bool warmup) const {
  const auto& group = warmup ? warmup_ : steady_;
  const auto it = group.find(stage);
  LatencySummary summary;
  if (it == group.end() || it->second.empty()) return summary;
  std::vector<double> values = it->second;
  summary.frames = static_cast<int64_t>(values.size());
  summary.mean_ms = std::accumulate(values.begin(), values.end(), 0.0) / values.size();
  summary.p50_ms = NearestRankQuantile(values, 0.50);
  summary.p90_ms = NearestRankQuantile(values, 0.90);
  summary.p99_ms = NearestRankQuantile(values, 0.99);
  summary.max_ms = values.back();
  return summary;
}

}  // namespace stereodet
