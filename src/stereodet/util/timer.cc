#include "stereodet/util/timer.h"

#include <fmt/format.h>

#include <algorithm>
#include <vector>

namespace stereodet {

void StageTimes::Add(const std::string& stage, double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  Stage& s = stages_[stage];
  s.total_s += seconds;
  ++s.count;
  first_seen_.emplace(stage, static_cast<int>(first_seen_.size()));
}

std::map<std::string, StageTimes::Stage> StageTimes::Snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stages_;
}

std::string StageTimes::Format() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::pair<int, std::string>> order;
  for (const auto& [name, index] : first_seen_) order.emplace_back(index, name);
  std::sort(order.begin(), order.end());
  std::string out;
  for (const auto& [index, name] : order) {
    const Stage& s = stages_.at(name);
    out += fmt::format("  {:<16} {:9.2f} ms/call  x {:<6} = {:8.2f} s\n", name,
                       s.count > 0 ? 1e3 * s.total_s / s.count : 0.0, s.count, s.total_s);
  }
  return out;
}

}  // namespace stereodet
