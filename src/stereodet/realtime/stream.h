// `stereodet run`: one detector over a stream of stereo pairs, as a pipeline of stages on threads
// with bounded queues, so that reading and stereo matching of frame t + 1 overlap the network on
// frame t:
//
//   reader (FrameSource::Next: read, decode)  ->  prepare (Detector::Prepare: stereo, encoding)
//     ->  network (Detector::Run: network, decoding)  ->  the caller's thread (FrameSink: write)
//
// Frames reach the sink in source order, each once. Without `realtime` every frame is processed
// as fast as the slowest stage allows (the queues block the reader). With `realtime` the reader
// replays the source at its frame rate and a frame that arrives while the previous one still
// waits for the prepare stage replaces it (the latest frame wins; the replaced one is counted as
// dropped and never reaches the sink).
//
// Threads: the three stage threads, and LibTorch's own threads inside the network stage
// (DetectorOptions::threads); OpenCV's matcher runs on the prepare thread (with OpenCV's threads).
// On 2 cores the network and the stereo of the next frame each get about one: see docs/realtime.md.
#ifndef STEREODET_REALTIME_STREAM_H_
#define STEREODET_REALTIME_STREAM_H_

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "stereodet/models/detector.h"
#include "stereodet/realtime/frame_source.h"
#include "stereodet/realtime/latency.h"
#include "stereodet/util/progress.h"

namespace stereodet {

struct StreamOptions {
  bool realtime = false;   // replay at the source's fps, dropping frames the detector misses
  int queue_capacity = 2;  // frames waiting between two stages (realtime: 1)
  int warmup_frames = 5;   // the first frames' latencies are reported apart
  // A frame the source could not give (a missing or broken file, a pair of two sizes) or the
  // detector refused stops the stream with an error naming it; otherwise it is reported in its
  // line (StreamFrame::error) and the stream goes on.
  bool strict = false;
  // Every this many seconds a line of the latency so far on `progress.stream` (0 = only the
  // progress bar).
  double report_interval_s = 0.0;
  ProgressOptions progress;
  void Check() const;  // throws std::invalid_argument naming the field
};

// One frame as the sink gets it: the source's record (its images released), the detector's result
// (empty objects when `error` is set) and the frame's latency per stage, ms: read (reading and
// decoding), stereo, encode, network, decode (the detector's stage times), wait (in the queues
// between the stages), end_to_end (from the moment the frame was due, or its read began without
// realtime, to the sink).
struct StreamFrame {
  SourceFrame source;
  DetectResult result;
  std::map<std::string, double> latency_ms;
  const std::string& error() const { return source.error; }
};
using FrameSink = std::function<void(const StreamFrame& frame)>;

struct StreamSummary {
  std::string source;          // FrameSource::Describe()
  int64_t frames_read = 0;     // frames the source gave
  int64_t frames_written = 0;  // frames the sink got (with or without error)
  int64_t frames_failed = 0;   // of those, with an error
  int64_t frames_dropped = 0;  // replaced by a later frame (realtime only)
  double seconds = 0.0;        // the stream's wall-clock time
  bool interrupted = false;    // stopped by `stop` (Ctrl-C) before the source ended
  LatencyRecorder latency;     // the sink's frames without error, per stage
  double FramesPerSecond() const { return seconds > 0 ? frames_written / seconds : 0.0; }
};

// Runs `detector` over `source`, calling `sink` on this thread for every frame in order. Returns
// when the source ends, or soon after `stop` becomes true (the frames in flight are finished and
// given to the sink first). Throws what the sink throws and, with `strict`, std::runtime_error
// naming the first frame that failed, after the stage threads have stopped.
StreamSummary RunStream(Detector& detector, FrameSource& source, const StreamOptions& options,
                        const FrameSink& sink, const std::atomic<bool>* stop = nullptr);

// A frame as one JSON line (no newline): {"index", "id", "timestamp_s", "objects": [{"type",
// "score", "box_2d": [left, top, right, bottom] px, and for 3D objects "dimensions_m": [h, w, l],
// "location_m": [x, y, z] (rectified camera frame, bottom centre), "rotation_y", "alpha"}],
// "latency_ms": {stage: ms}, and "error" when the frame failed}. Numbers are rounded as KITTI's
// files round them (px and m to 0.01, angles and scores to 1e-6), latencies to 0.001 ms.
std::string StreamFrameJson(const StreamFrame& frame);

// The latency report: per stage p50 / p90 / p99 / max / mean ms over the frames after the
// warm-up, the warm-up's apart, frames, frames/s and drops. As a text table, and as JSON
// {"source", "frames_read", "frames_written", "frames_failed", "frames_dropped", "seconds",
// "frames_per_s", "interrupted", "warmup_frames", "stages": {stage: {frames, p50_ms, p90_ms,
// p99_ms, max_ms, mean_ms}}, "warmup_stages": {...}}.
std::string FormatLatencyTable(const StreamSummary& summary);
std::string StreamSummaryJson(const StreamSummary& summary, int warmup_frames);

}  // namespace stereodet

#endif  // STEREODET_REALTIME_STREAM_H_
