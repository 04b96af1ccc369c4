// Wall-clock timers and a thread-safe per-stage time accumulator ("disparity 41.2 ms/frame").
#ifndef STEREODET_UTIL_TIMER_H_
#define STEREODET_UTIL_TIMER_H_

#include <chrono>
#include <map>
#include <mutex>
#include <string>

namespace stereodet {

class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  void Restart() { start_ = std::chrono::steady_clock::now(); }
  double ElapsedSeconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  double ElapsedMs() const { return 1e3 * ElapsedSeconds(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Sums the time spent in named stages over many frames, from any number of threads.
class StageTimes {
 public:
  struct Stage {
    double total_s = 0.0;
    long count = 0;
  };

  void Add(const std::string& stage, double seconds);
  // Stages in name order.
  std::map<std::string, Stage> Snapshot() const;
  // One line per stage: "  disparity      41.2 ms/call  x 3769  = 155.3 s", in the order stages
  // were first added.
  std::string Format() const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, Stage> stages_;
  std::map<std::string, int> first_seen_;
};

// Adds the time from construction to destruction to `times` under `stage`.
class ScopedStage {
 public:
  ScopedStage(StageTimes& times, std::string stage) : times_(times), stage_(std::move(stage)) {}
  ~ScopedStage() { times_.Add(stage_, timer_.ElapsedSeconds()); }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageTimes& times_;
  std::string stage_;
  Timer timer_;
};

}  // namespace stereodet

#endif  // STEREODET_UTIL_TIMER_H_
