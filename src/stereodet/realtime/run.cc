#include "stereodet/realtime/run.h"

#include <fmt/format.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "stereodet/kitti/label_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/version.h"

namespace stereodet {

namespace fs = std::filesystem;

namespace {

// `run --out FILE` writes in place (a stream can be followed as it grows), so it replaces only
// an empty file or one it wrote: a first line that is a frame line (index, objects, latency_ms).
// A device or a FIFO is written to as it is.
void CheckJsonLinesTarget(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) return;
  STEREODET_CHECK_IO(!fs::is_directory(path, ec))
      << "run: --out " << path.string() << " is a folder; give a file (or - for stdout)";
  // A device or a pipe (/dev/null, a FIFO a consumer reads) is a stream, not a file to keep.
  if (!fs::is_regular_file(path, ec)) return;
  // The first line whole (a frame with many objects is a long line).
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  if (first.empty() && in.eof()) return;
  const nlohmann::json j = nlohmann::json::parse(first, nullptr, /*allow_exceptions=*/false);
  STEREODET_CHECK_IO(j.is_object() && j.contains("index") && j.contains("objects") &&
                     j.contains("latency_ms"))
      << "run: --out " << path.string()
      << " exists and is not a stream `run` wrote (its first line is not a frame line); "
         "run replaces only its own output: give a new file";
}

// The JSON Lines output: stdout or a file, one whole line per write, flushed.
class LineWriter {
 public:
  explicit LineWriter(const std::string& out) {
    if (out == "-") {
      file_ = stdout;
      return;
    }
    CheckJsonLinesTarget(out);
    file_ = std::fopen(out.c_str(), "w");
    STEREODET_CHECK_IO(file_ != nullptr) << "run: cannot write --out " << out;
    owned_ = true;
    name_ = out;
  }
  ~LineWriter() {
    if (owned_) std::fclose(file_);
  }
  LineWriter(const LineWriter&) = delete;
  LineWriter& operator=(const LineWriter&) = delete;

  void Write(std::string line) {
    line += '\n';
    // One write of the whole line: a reader, or a Ctrl-C, never sees half of one.
    const bool ok =
        std::fwrite(line.data(), 1, line.size(), file_) == line.size() && std::fflush(file_) == 0;
    STEREODET_CHECK_IO(ok) << "run: cannot write " << (owned_ ? name_ : "stdout")
                           << " (disk full, or the reader went away)";
  }

 private:
  std::FILE* file_ = nullptr;
  bool owned_ = false;
  std::string name_;
};

}  // namespace

void RunOptions::Check() const {
  STEREODET_CHECK(!model_dir.empty()) << "--model is required";
  STEREODET_CHECK(!out.empty()) << "--out must name a file or - (stdout)";
  detector.Check();
  stream.Check();
}

RunSummary RunDetectorStream(const RunOptions& options, const std::atomic<bool>* stop) {
  options.Check();
  // Everything that can be refused is refused before the first frame: the model, the source
  // (and its calibration against its first frame), the outputs.
  Detector detector = Detector::Open(options.model_dir, options.detector);
  RunSummary summary;
  summary.family = detector.family();
  summary.input = detector.input();
  FrameSourceOptions source_options = options.source;
  source_options.needs = detector.needs();
  const std::unique_ptr<FrameSource> source = OpenFrameSource(source_options);

  std::optional<StagedFolder> kitti;
  if (!options.kitti_out.empty()) {
    std::vector<std::pair<std::string, fs::path>> inputs = {{"--model", options.model_dir}};
    if (!options.source.data_root.empty()) {
      inputs.push_back({"--data", options.source.data_root / options.source.subset});
    }
    CheckOutputDoesNotOverlapInputs("--kitti-out", options.kitti_out, inputs);
    kitti.emplace(options.kitti_out, "run", DetectionFolderMakers());
  }
  LineWriter lines(options.out);
  RunManifest manifest;
  manifest.tool = "run";
  manifest.version = StereodetVersion();
  manifest.command_line = options.command_line;
  manifest.inputs = {{"model", options.model_dir.string()}, {"source", source->Describe()}};

  summary.stream = RunStream(
      detector, *source, options.stream,
      [&](const StreamFrame& frame) {
        lines.Write(StreamFrameJson(frame));
        if (kitti && frame.error().empty()) {
          const fs::path path = kitti->path() / (frame.source.frame.id + ".txt");
          const std::string text = FormatObjects(frame.result.objects);
          WriteFileAtomically(path, text);
          manifest.frames.push_back({frame.source.frame.id, HashHex(Fnv1a64(text))});
        }
      },
      stop);

  if (kitti) {
    manifest.settings_json = fmt::format(
        R"({{"model_weights_fnv1a64": "{}", "family": "{}", "input": "{}", "blur_sigma_px": {}, )"
        R"("device": "{}", "realtime": {}, "interrupted": {}, "frames_dropped": {}, )"
        R"("frames_failed": {}}})",
        detector.weights_fnv1a64(), summary.family, summary.input, options.detector.blur_sigma_px,
        options.detector.device, options.stream.realtime, summary.stream.interrupted,
        summary.stream.frames_dropped, summary.stream.frames_failed);
    WriteRunManifest(kitti->path(), manifest);
    kitti->Commit();
  }
  if (!options.summary_json.empty()) {
    WriteFileAtomically(options.summary_json,
                        StreamSummaryJson(summary.stream, options.stream.warmup_frames));
  }
  return summary;
}

}  // namespace stereodet
