#include "stereodet/realtime/stream.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>
#include <utility>

#include "stereodet/util/check.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

// A queue between two stages: Push blocks while it is full, Pop while it is empty; after Close,
// Push refuses and Pop drains what is left. PushLatest never blocks: a full queue loses its
// oldest item (the latest frame wins), counted in `dropped`.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(capacity) {}

  bool Push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  bool PushLatest(T item, int64_t& dropped) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return false;
    while (items_.size() >= capacity_) {
      items_.pop_front();
      ++dropped;
    }
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  std::optional<T> Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
    not_full_.notify_all();
  }

 private:
  const size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<T> items_;
  bool closed_ = false;
};

// A frame on its way through the stages.
struct InFlight {
  StreamFrame frame;
  Clock::time_point due, read_done, prepare_start, prepare_done, network_start, network_done;
  std::unique_ptr<Detector::PreparedBatch> prepared;
};
using Item = std::unique_ptr<InFlight>;

// The first exception of any stage, kept to be rethrown on the caller's thread.
class FirstError {
 public:
  void Set(std::exception_ptr error) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_) error_ = std::move(error);
  }
  std::exception_ptr Get() {
    std::lock_guard<std::mutex> lock(mutex_);
    return error_;
  }

 private:
  std::mutex mutex_;
  std::exception_ptr error_;
};

// Releases a frame's images once the detector has what it needs: the sink gets the record only.
void ReleaseImages(StereoFrame& frame) {
  frame.left.release();
  frame.right.release();
  frame.height_code.release();
  frame.points.reset();
}

// `value` to 1 / scale (scale 100: 0.01), through a division so that the result is the double
// nearest the decimal (it prints as that decimal).
double Round(double value, double scale) { return std::round(value * scale) / scale; }

}  // namespace

void StreamOptions::Check() const {
  STEREODET_CHECK(queue_capacity >= 1) << "queue capacity must be >= 1, got " << queue_capacity;
  STEREODET_CHECK(warmup_frames >= 0) << "warm-up frames must be >= 0, got " << warmup_frames;
  STEREODET_CHECK(std::isfinite(report_interval_s) && report_interval_s >= 0)
      << "report interval must be >= 0 s, got " << report_interval_s;
}

StreamSummary RunStream(Detector& detector, FrameSource& source, const StreamOptions& options,
                        const FrameSink& sink, const std::atomic<bool>* stop) {
  options.Check();
  StreamSummary summary;
  summary.source = source.Describe();
  summary.latency = LatencyRecorder(options.warmup_frames);
  // Realtime: one slot between every two stages, so that at most one frame waits before each
  // (latency stays bounded when a stage is slower than the source: frames are dropped at the first
  // slot instead of piling up); without it the queues block the reader.
  const size_t capacity = options.realtime ? 1 : static_cast<size_t>(options.queue_capacity);
  BoundedQueue<Item> to_prepare(capacity);
  BoundedQueue<Item> to_network(capacity);
  BoundedQueue<Item> to_sink(capacity);
  std::atomic<bool> abort{false};
  std::atomic<int64_t> frames_read{0};
  int64_t dropped = 0;  // by the reader only, read after it is joined
  FirstError first_error;
  auto stopping = [&] { return abort.load() || (stop != nullptr && stop->load()); };
  const Clock::time_point start = Clock::now();
  const double fps = source.fps();

  std::thread reader([&] {
    try {
      for (int64_t index = 0; !stopping(); ++index) {
        auto item = std::make_unique<InFlight>();
        item->due = Clock::now();
        if (options.realtime) {
          // The frame is due at its place in the source's time line; reading it is part of its
          // latency, as a camera's frame is waiting from the moment it was taken.
          item->due = start + std::chrono::duration_cast<Clock::duration>(
                                  std::chrono::duration<double>(index / fps));
          // In short naps, so that a stop is seen within 50 ms even at a slow frame rate.
          while (!stopping() && Clock::now() < item->due) {
            std::this_thread::sleep_for(
                std::min<Clock::duration>(item->due - Clock::now(), std::chrono::milliseconds(50)));
          }
          if (stopping()) break;
        }
        std::optional<SourceFrame> frame = source.Next();
        if (!frame) break;
        item->read_done = Clock::now();
        item->frame.source = std::move(*frame);
        ++frames_read;
        const bool pushed = options.realtime ? to_prepare.PushLatest(std::move(item), dropped)
                                             : to_prepare.Push(std::move(item));
        if (!pushed) break;
      }
    } catch (...) {
      first_error.Set(std::current_exception());
      abort = true;
    }
    to_prepare.Close();
  });

  std::thread preparer([&] {
    try {
      while (std::optional<Item> item = to_prepare.Pop()) {
        InFlight& f = **item;
        f.prepare_start = Clock::now();
        if (f.frame.error().empty()) {
          try {
            f.prepared = detector.Prepare({f.frame.source.frame});
          } catch (const std::exception& e) {
            f.frame.source.error =
                UserMessage(e);  // a frame the detector refuses; the stream goes on
          }
        }
        f.prepare_done = Clock::now();
        ReleaseImages(f.frame.source.frame);
        if (!to_network.Push(std::move(*item))) break;
      }
    } catch (...) {
      first_error.Set(std::current_exception());
      abort = true;
      to_prepare.Close();
    }
    to_network.Close();
  });

  std::thread network([&] {
    try {
      while (std::optional<Item> item = to_network.Pop()) {
        InFlight& f = **item;
        f.network_start = Clock::now();
        if (f.prepared) {
          try {
            std::vector<DetectResult> results = detector.Run(std::move(f.prepared));
            f.frame.result = std::move(results.at(0));
          } catch (const std::exception& e) {
            f.frame.source.error = UserMessage(e);
          }
        }
        f.network_done = Clock::now();
        if (!to_sink.Push(std::move(*item))) break;
      }
    } catch (...) {
      first_error.Set(std::current_exception());
      abort = true;
      to_network.Close();
    }
    to_sink.Close();
  });

  // The sink, on this thread.
  ProgressReporter progress("run", std::max<int64_t>(source.size(), 0), options.progress);
  Clock::time_point last_report = start;
  try {
    while (std::optional<Item> item = to_sink.Pop()) {
      InFlight& f = **item;
      StreamFrame& frame = f.frame;
      frame.result.id = frame.source.frame.id;
      const Clock::time_point done = Clock::now();
      frame.latency_ms["read"] = frame.source.read_s * 1e3;
      if (frame.error().empty()) {
        const DetectStageTimes& t = frame.result.times;
        frame.latency_ms["stereo"] = t.stereo_s * 1e3;
        frame.latency_ms["encode"] = t.encode_s * 1e3;
        frame.latency_ms["network"] = t.network_s * 1e3;
        frame.latency_ms["decode"] = t.decode_s * 1e3;
        frame.latency_ms["wait"] = Ms(f.prepare_start - f.read_done) +
                                   Ms(f.network_start - f.prepare_done) + Ms(done - f.network_done);
      }
      frame.latency_ms["end_to_end"] = Ms(done - f.due);
      if (!frame.error().empty()) {
        ++summary.frames_failed;
        STEREODET_CHECK_IO(!options.strict)
            << "frame " << frame.source.index << " (" << frame.source.frame.id
            << "): " << frame.error() << " (--strict stops at the first frame that fails)";
      }
      sink(frame);
      ++summary.frames_written;
      if (frame.error().empty()) summary.latency.Record(frame.latency_ms);
      progress.Add(1, fmt::format("end to end {:.1f} ms", frame.latency_ms["end_to_end"]));
      if (options.report_interval_s > 0 && options.progress.stream != nullptr &&
          std::chrono::duration<double>(done - last_report).count() >= options.report_interval_s) {
        last_report = done;
        const LatencySummary e2e = summary.latency.Summary("end_to_end");
        std::fprintf(options.progress.stream,
                     "run: %lld frames, %.2f frames/s, end to end p50 %.1f ms p99 %.1f ms\n",
                     static_cast<long long>(summary.frames_written),
                     summary.frames_written / std::chrono::duration<double>(done - start).count(),
                     e2e.p50_ms, e2e.p99_ms);
      }
    }
  } catch (...) {
    first_error.Set(std::current_exception());
    abort = true;
    to_prepare.Close();
    to_network.Close();
    to_sink.Close();
  }
  // Whatever ended the stream, every stage finishes before anything is returned or thrown.
  abort = abort || (stop != nullptr && stop->load());
  to_prepare.Close();
  reader.join();
  preparer.join();
  network.join();
  progress.Finish();
  if (std::exception_ptr error = first_error.Get()) std::rethrow_exception(error);
  summary.frames_read = frames_read;
  summary.frames_dropped = dropped;
  summary.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  summary.interrupted = stop != nullptr && stop->load();
  return summary;
}

std::string StreamFrameJson(const StreamFrame& frame) {
  nlohmann::ordered_json j;
  j["index"] = frame.source.index;
  j["id"] = frame.source.frame.id;
  j["timestamp_s"] = Round(frame.source.frame.timestamp_s, 1e6);
  nlohmann::ordered_json objects = nlohmann::ordered_json::array();
  for (const Object& o : frame.result.objects) {
    nlohmann::ordered_json jo;
    jo["type"] = o.type;
    jo["score"] = Round(o.score.value_or(0.0), 1e6);
    jo["box_2d"] = {Round(o.box.left, 100), Round(o.box.top, 100), Round(o.box.right, 100),
                    Round(o.box.bottom, 100)};
    if (o.Has3D()) {
      jo["dimensions_m"] = {Round(o.box3d.h, 100), Round(o.box3d.w, 100), Round(o.box3d.l, 100)};
      jo["location_m"] = {Round(o.box3d.location.x(), 100), Round(o.box3d.location.y(), 100),
                          Round(o.box3d.location.z(), 100)};
      jo["rotation_y"] = Round(o.box3d.rotation_y, 1e6);
      jo["alpha"] = Round(o.alpha, 1e6);
    }
    objects.push_back(std::move(jo));
  }
  j["objects"] = std::move(objects);
  nlohmann::ordered_json latency;
  for (const char* stage :
       {"read", "stereo", "encode", "network", "decode", "wait", "end_to_end"}) {
    const auto it = frame.latency_ms.find(stage);
    if (it != frame.latency_ms.end()) latency[stage] = Round(it->second, 1e3);
  }
  j["latency_ms"] = std::move(latency);
  if (!frame.error().empty()) j["error"] = frame.error();
  return j.dump();
}

namespace {

const char* const kStages[] = {"read",   "stereo", "encode",    "network",
                               "decode", "wait",   "end_to_end"};

nlohmann::ordered_json StagesJson(const LatencyRecorder& latency, bool warmup) {
  nlohmann::ordered_json stages = nlohmann::ordered_json::object();
  for (const char* stage : kStages) {
    const LatencySummary s = latency.Summary(stage, warmup);
    if (s.frames == 0) continue;
    stages[stage] = {{"frames", s.frames},
                     {"p50_ms", Round(s.p50_ms, 1e3)},
                     {"p90_ms", Round(s.p90_ms, 1e3)},
                     {"p99_ms", Round(s.p99_ms, 1e3)},
                     {"max_ms", Round(s.max_ms, 1e3)},
                     {"mean_ms", Round(s.mean_ms, 1e3)}};
  }
  return stages;
}

}  // namespace

std::string FormatLatencyTable(const StreamSummary& summary) {
  std::string out = fmt::format("{:<11} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9}\n", "stage", "frames",
                                "p50 ms", "p90 ms", "p99 ms", "max ms", "mean ms");
  for (const bool warmup : {false, true}) {
    bool any = false;
    for (const char* stage : kStages) {
      const LatencySummary s = summary.latency.Summary(stage, warmup);
      if (s.frames == 0) continue;
      if (warmup && !any) out += "warm-up (the first frames, apart):\n";
      any = true;
      out += fmt::format("{:<11} {:>7} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f}\n", stage,
                         s.frames, s.p50_ms, s.p90_ms, s.p99_ms, s.max_ms, s.mean_ms);
    }
  }
  out += fmt::format("{} frames in {:.2f} s: {:.2f} frames/s; {} read, {} failed, {} dropped{}\n",
                     summary.frames_written, summary.seconds, summary.FramesPerSecond(),
                     summary.frames_read, summary.frames_failed, summary.frames_dropped,
                     summary.interrupted ? " (interrupted)" : "");
  return out;
}

std::string StreamSummaryJson(const StreamSummary& summary, int warmup_frames) {
  nlohmann::ordered_json j;
  j["source"] = summary.source;
  j["frames_read"] = summary.frames_read;
  j["frames_written"] = summary.frames_written;
  j["frames_failed"] = summary.frames_failed;
  j["frames_dropped"] = summary.frames_dropped;
  j["seconds"] = Round(summary.seconds, 1e3);
  j["frames_per_s"] = Round(summary.FramesPerSecond(), 1e3);
  j["interrupted"] = summary.interrupted;
  j["warmup_frames"] = warmup_frames;
  j["stages"] = StagesJson(summary.latency, false);
  j["warmup_stages"] = StagesJson(summary.latency, true);
  return j.dump(2) + "\n";
}

}  // namespace stereodet
