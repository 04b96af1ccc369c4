// `stereodet run --model DIR SOURCE`: one detector of any family over a stream of stereo pairs,
// a JSON line per frame as it goes, per-stage latency at the end (realtime/run.h).
//   stereodet run --model DIR [--data ROOT --split val | --left L --right R --calib F |
//                  --video F --calib F | --left-video L --right-video R --calib F |
//                  --camera N --calib F] [--out FILE] [--kitti-out DIR] [--summary FILE]
//                 [--realtime [--fps F]] [--strict] [--threads N] [--device cpu|cuda]
// Ctrl-C or SIGTERM stops the stream cleanly: the frames in flight are finished and written (no
// half line), the summary is printed; a second one ends the process at once.
#include <signal.h>

#include <atomic>
#include <cstdio>
#include <memory>
#include <string>

#include "stereodet/cli/commands.h"
#include "stereodet/models/train_common.h"
#include "stereodet/realtime/run.h"

namespace stereodet::cli {
namespace {

std::atomic<bool> g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free);

void OnStopSignal(int signal_number) {
  g_stop = true;
  // A second Ctrl-C is the default action: the user insists.
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigaction(signal_number, &action, nullptr);
}

void InstallStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;  // reads and writes in flight go on; the stages see g_stop
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

struct RunArgs {
  RunOptions options;
  bool quiet = false;
};

void Run(RunArgs& a) {
  RunOptions& options = a.options;
  options.command_line = ProcessCommandLine();
  if (a.quiet) options.stream.progress.stream = nullptr;
  const std::string warning = UnfinishedTrainingWarning(options.model_dir);
  if (!warning.empty()) std::fputs(warning.c_str(), stderr);
  InstallStopHandlers();
  const RunSummary summary = RunDetectorStream(options, &g_stop);
  if (!a.quiet) {
    std::fprintf(stderr, "run: %s model (%s), %s\n", summary.family.c_str(), summary.input.c_str(),
                 summary.stream.source.c_str());
    std::fputs(FormatLatencyTable(summary.stream).c_str(), stderr);
  }
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  RunOptions& o = args->options;
  CLI::App* cmd = app.add_subcommand("run", CommandDescription("run"));
  cmd->add_option("--model", o.model_dir, "a model folder of any family (model.json names it)")
      ->required();
  const char* kSource = "Source (one)";
  cmd->add_option("--data", o.source.data_root, "a KITTI-format folder (with --split)")
      ->group(kSource);
  cmd->add_option("--split", o.source.split, "with --data: ImageSets/SPLIT.txt or a split file")
      ->capture_default_str()
      ->group(kSource);
  cmd->add_option("--subset", o.source.subset, "with --data: training or testing")
      ->capture_default_str()
      ->group(kSource);
  cmd->add_option("--left", o.source.left,
                  "left images: a folder (its .png/.jpg, sorted) or a quoted glob")
      ->group(kSource);
  cmd->add_option("--right", o.source.right, "right images, as --left (the same count)")
      ->group(kSource);
  cmd->add_option("--video", o.source.video,
                  "one stereo video, left | right side by side (OpenCV VideoCapture)")
      ->group(kSource);
  cmd->add_option("--left-video", o.source.left_video, "the left camera's video")->group(kSource);
  cmd->add_option("--right-video", o.source.right_video, "the right camera's video, in sync")
      ->group(kSource);
  cmd->add_option("--camera", o.source.camera,
                  "a camera index (a side-by-side stereo camera; OpenCV VideoCapture)")
      ->group(kSource);
  cmd->add_option("--calib", o.source.calib,
                  "a KITTI calib file for every frame of a non-KITTI source (P2, P3, ...)")
      ->group(kSource);
  cmd->add_option("--fps", o.source.fps,
                  "the source's frame rate (sequences: 10, KITTI's; videos: their own)")
      ->group(kSource);
  cmd->add_flag("--preload", o.source.preload,
                "read and decode every frame first, then stream them from memory (benchmarks: "
                "detection alone; about 2.8 MB a 1242 x 375 pair: use with --max-frames)")
      ->group(kSource);
  cmd->add_option("--max-frames", o.source.max_frames, "stop after N frames (0 = all)")
      ->capture_default_str()
      ->group(kSource);

  cmd->add_option("--out", o.out, "JSON Lines, one line per frame as it is done (- = stdout)")
      ->capture_default_str();
  cmd->add_option("--kitti-out", o.kitti_out,
                  "also the frames' KITTI detection files (ID.txt) and run.json, in this folder");
  cmd->add_option("--summary", o.summary_json, "the latency summary as JSON, in this file");
  cmd->add_flag("--realtime", o.stream.realtime,
                "replay the source at its frame rate; frames the detector cannot keep up with "
                "are dropped (the latest wins) and counted");
  cmd->add_flag("--strict", o.stream.strict,
                "stop at the first frame that cannot be read or detected (default: report it in "
                "its line and go on)");
  cmd->add_option("--warmup", o.stream.warmup_frames,
                  "the first N frames' latencies are reported apart")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--queue", o.stream.queue_capacity, "frames waiting between two stages")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--report-every", o.stream.report_interval_s,
                  "a latency line on stderr every S seconds (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--threads", o.detector.threads, "LibTorch's threads (0 = all cores)")
      ->capture_default_str();
  cmd->add_option("--device", o.detector.device, "cpu or cuda")
      ->check(CLI::IsMember({"cpu", "cuda"}))
      ->capture_default_str();
  cmd->add_option("--blur-sigma", o.detector.blur_sigma_px,
                  "Gaussian blur of the network's image, px (stereo stays sharp); 0 = none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--score-calibration", o.detector.calibration,
                  "a score calibration file of `stereodet calibrate --fit`: each detection's "
                  "calibrated probability instead of the network's score (as `detect "
                  "--calibration` writes them; docs/metrics.md, Calibrators)")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--quiet", args->quiet, "no progress or latency table on stderr");
  cmd->callback([args] { Run(*args); });
}

}  // namespace stereodet::cli
