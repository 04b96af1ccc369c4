#include "stereodet/util/progress.h"

#include <fmt/format.h>
#include <unistd.h>

namespace stereodet {

namespace {
using Clock = std::chrono::steady_clock;

std::string FormatDuration(double seconds) {
  if (!(seconds >= 0) || seconds > 1e7) return "?";
  const auto s = static_cast<int64_t>(seconds + 0.5);
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, (s / 60) % 60, s % 60);
  return fmt::format("{}:{:02}", s / 60, s % 60);
}
}  // namespace

ProgressReporter::ProgressReporter(std::string label, int64_t total, ProgressOptions options)
    : label_(std::move(label)), total_(total), options_(options) {
  start_ = last_draw_ = Clock::now();
  if (options_.stream != nullptr) {
    switch (options_.mode) {
      case ProgressOptions::Mode::kTerminal:
        terminal_ = true;
        break;
      case ProgressOptions::Mode::kPlain:
        terminal_ = false;
        break;
      case ProgressOptions::Mode::kAuto:
        terminal_ = ::isatty(::fileno(options_.stream)) != 0;
        break;
    }
  }
}

ProgressReporter::~ProgressReporter() {
  try {
    Finish();
  } catch (...) {
    // A failing stream must not turn into std::terminate during unwinding.
  }
}

double ProgressReporter::ElapsedSeconds() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void ProgressReporter::Add(int64_t n, const std::string& status) {
  const int64_t done = done_.fetch_add(n) + n;
  if (options_.stream == nullptr) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  if (!status.empty()) status_ = status;
  const auto now = Clock::now();
  const double since_draw = std::chrono::duration<double>(now - last_draw_).count();
  if (terminal_) {
    if (since_draw >= 0.1 || (total_ > 0 && done >= total_)) Draw(false);
    return;
  }
  const int percent = total_ > 0 ? static_cast<int>(100 * done / total_) : -1;
  const int step = std::max(1, options_.plain_percent_step);
  const bool new_step = percent >= 0 && percent / step > last_percent_printed_ / step;
  if (new_step || since_draw >= options_.plain_interval_s) {
    if (percent >= 0) last_percent_printed_ = percent;
    Draw(false);
  }
}

void ProgressReporter::Finish() {
  if (options_.stream == nullptr) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  Draw(true);
}

void ProgressReporter::Draw(bool final_line) {
  last_draw_ = Clock::now();
  const int64_t done = done_.load();
  const double elapsed = ElapsedSeconds();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  std::string line = label_ + "  ";
  if (total_ > 0) {
    line += fmt::format("{}/{}  {:3}%", done, total_, static_cast<int>(100 * done / total_));
  } else {
    line += fmt::format("{}", done);
  }
  line += fmt::format("  {:.1f}/s", rate);
  if (final_line) {
    line += "  in " + FormatDuration(elapsed);
  } else if (total_ > 0 && rate > 0) {
    line += "  ETA " + FormatDuration((total_ - done) / rate);
  }
  if (!status_.empty()) line += "  " + status_;
  if (terminal_) {
    // \r and "erase to end of line" redraw in place; the final line ends with a newline.
    fmt::print(options_.stream, "\r{}\x1b[K{}", line, final_line ? "\n" : "");
  } else {
    fmt::print(options_.stream, "{}\n", line);
  }
  std::fflush(options_.stream);
}

}  // namespace stereodet
