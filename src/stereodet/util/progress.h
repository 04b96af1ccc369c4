// Progress reporting for long jobs (dataset generation, stereo over a split, training, evaluation).
//
// On a terminal it redraws one line on stderr ("label  1234/3769  33%  41.2/s  ETA 1:02"), at most
// ten times a second; otherwise (logs, CI) it prints a plain line at every 10% and at most every
// 30 s, so logs stay short. Thread-safe: Add() may be called from any worker thread.
#ifndef STEREODET_UTIL_PROGRESS_H_
#define STEREODET_UTIL_PROGRESS_H_

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

namespace stereodet {

struct ProgressOptions {
  // Where to draw. nullptr silences the reporter (tests, --quiet).
  std::FILE* stream = stderr;
  // Redraw in place; by default only when `stream` is a terminal.
  enum class Mode { kAuto, kTerminal, kPlain } mode = Mode::kAuto;
  // Plain mode: print at every `plain_percent_step` percent, and at least every `plain_interval_s`.
  int plain_percent_step = 10;
  double plain_interval_s = 30.0;
};

class ProgressReporter {
 public:
  // `total` may be 0 when unknown (then no percentage or ETA is shown).
  ProgressReporter(std::string label, int64_t total, ProgressOptions options = {});
  ~ProgressReporter();  // calls Finish() if the caller did not
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  // Counts `n` more units done. `status` (e.g. "loss 0.41"), if not empty, replaces the status
  // text.
  void Add(int64_t n = 1, const std::string& status = "");
  // Prints the final line (count, rate, elapsed time). Idempotent.
  void Finish();

  int64_t done() const { return done_.load(); }
  double ElapsedSeconds() const;

 private:
  void Draw(bool final_line);

  std::string label_;
  int64_t total_;
  ProgressOptions options_;
  bool terminal_ = false;
  std::atomic<int64_t> done_{0};
  std::mutex mutex_;  // guards everything below and the stream
  std::string status_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int last_percent_printed_ = -1;
  bool finished_ = false;
};

}  // namespace stereodet

#endif  // STEREODET_UTIL_PROGRESS_H_
