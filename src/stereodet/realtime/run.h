// `stereodet run` as one library call: open the model and the source, stream the frames through
// the detector (stream.h), write one JSON line per frame as it goes (stdout or a file), the
// frames' KITTI files if asked, and the latency summary.
//
//   RunOptions options;
//   options.model_dir = "models/ssd-rgbh-learned";
//   options.source.data_root = "data/synth";  options.source.split = "val";
//   options.out = "detections.jsonl";
//   const RunSummary summary = RunDetectorStream(options);
//   std::fputs(FormatLatencyTable(summary.stream).c_str(), stderr);
#ifndef STEREODET_REALTIME_RUN_H_
#define STEREODET_REALTIME_RUN_H_

#include <atomic>
#include <filesystem>
#include <string>

#include "stereodet/models/detector.h"
#include "stereodet/realtime/frame_source.h"
#include "stereodet/realtime/stream.h"

namespace stereodet {

struct RunOptions {
  std::filesystem::path model_dir;  // any family (model.json's architecture)
  DetectorOptions detector;         // device, threads, blur, stereo, decoding
  FrameSourceOptions source;        // its `needs` are set from the model's
  StreamOptions stream;
  // The JSON Lines, one line per frame, flushed as each frame is done: "-" = stdout. A file is
  // written in place as the stream goes (so that it can be followed), and only over a file that
  // is empty or that `run` wrote (its first line is a frame line), or to a device or FIFO
  // (/dev/null, a pipe a consumer reads); anything else is refused.
  std::string out = "-";
  // The frames' KITTI detection files (ID.txt) and run.json (tool "run"), committed whole at the
  // end (also after Ctrl-C: run.json then says "interrupted" and lists the frames done). Empty =
  // none. A folder of detection files (run, detect) is replaced; anything else is refused.
  std::filesystem::path kitti_out;
  // The summary (StreamSummaryJson), written atomically at the end. Empty = none.
  std::filesystem::path summary_json;
  std::string command_line;  // for run.json
  void Check() const;        // throws std::invalid_argument naming the field
};

struct RunSummary {
  std::string family, input;  // the model's (Detector::family(), input())
  StreamSummary stream;
};

// Throws std::invalid_argument for bad options (naming the flag), std::runtime_error naming the
// file for a model, source or output that cannot be used, before the first frame; during the
// stream what RunStream throws.
RunSummary RunDetectorStream(const RunOptions& options, const std::atomic<bool>* stop = nullptr);

}  // namespace stereodet

#endif  // STEREODET_REALTIME_RUN_H_
