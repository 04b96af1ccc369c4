// The one table of `stereodet` commands, shared by the front end and its sibling executables.
#include <stdexcept>
#include <string>

#include "stereodet/cli/commands.h"

namespace stereodet::cli {

const char* ProgramName(Program program) {
  switch (program) {
    case Program::kFrontEnd:
      return "stereodet";
    case Program::kVision:
      return "stereodet-vision";
    case Program::kModels:
      return "stereodet-models";
  }
  return "stereodet";
}

std::optional<Program> ParseProgram(std::string_view text) {
  for (Program program : {Program::kFrontEnd, Program::kVision, Program::kModels}) {
    if (text == ProgramName(program)) return program;
  }
  return std::nullopt;
}

bool ProgramBuilt(Program program) {
  switch (program) {
    case Program::kFrontEnd:
    case Program::kVision:
      return true;
    case Program::kModels:
#ifdef STEREODET_BUILT_MODELS
      return true;
#else
      return false;
#endif
  }
  return false;
}

std::span<const Command> CommandTable() {
  // In the order a user meets them.
  static constexpr Command kCommands[] = {
      {"synth", Program::kVision,
       "Write synthetic KITTI-format street scenes: "
       "training/{image_2,image_3,label_2,calib,velodyne,"
       "disp_noc_0} and ImageSets/{train,val,trainval}.txt. Resumable; the same seed gives the "
       "same bytes on any number of threads."},
      {"stereo", Program::kVision,
       "Compute stereo features for every frame of a KITTI-format dataset: RGB-H images (rgbh/), "
       "depth and height codes for RGB-D (depth/, height/), stereo point clouds as velodyne .bin "
       "(velodyne/), KITTI-format disparity (disparity/), and the ground plane (ground/). "
       "Parallel, resumable (frames whose outputs exist are skipped), atomic writes. See "
       "docs/stereo.md."},
      {"info", Program::kFrontEnd,
       "Summarize a KITTI-format dataset: frames, objects per class and difficulty, a distance "
       "histogram, and any missing files or bad lines (non-zero exit if there are problems)."},
      {"eval", Program::kFrontEnd,
       "evaluate detections: KITTI-compatible AP, optimal matching, filters, Brier, calibration, "
       "3D error"},
      {"calibrate", Program::kFrontEnd,
       "fit score calibrators (temperature, Platt, isotonic) per class on one split's matched "
       "detections and write a calibration file that `eval --calibration` applies"},
      {"report", Program::kFrontEnd,
       "figures (SVG, PNG) and one self-contained HTML page of one or several `eval --out` "
       "results folders: PR, recall vs FP per frame, reliability and Brier, 3D error vs distance"},
      {"view", Program::kFrontEnd,
       "frame views of an `eval --out --records` results folder: labels and detections on the "
       "left image coloured TP / FP / FN with score and IoU, and the bird's-eye view with the "
       "points and 3D boxes (SVG, PNG); by default the worst frames"},
      {"train", Program::kModels, "train a detector on a KITTI-format split"},
      {"detect", Program::kModels,
       "run a trained detector, write KITTI detection files (`detect --model DIR ...`: the family "
       "model.json names)"},
      {"run", Program::kModels,
       "run a trained detector (any family) over a stream of stereo pairs (a KITTI split, image "
       "sequences, videos, a camera): JSON Lines as it goes, per-stage latency; --realtime drops "
       "frames it cannot keep up with"},
  };
  return kCommands;
}

std::string CommandDescription(std::string_view name) {
  for (const Command& command : CommandTable()) {
    if (command.name == name) return std::string(command.description);
  }
  throw std::logic_error("stereodet: command '" + std::string(name) +
                         "' is not in the command table (command_table.cc)");
}

}  // namespace stereodet::cli
