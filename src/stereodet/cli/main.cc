// stereodet: stereo features, detectors and safety-grade evaluation for KITTI-format data.
// The front end: runs info, eval, report and view itself (no OpenCV, no LibTorch loaded) and hands
// every other command to its sibling executable (see commands.h).
#include <string_view>
#include <utility>

#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"info", AddInfoCommand},
      {"eval", AddEvalCommand},
      {"report", AddReportCommand},
      {"view", AddViewCommand},
  };
  return RunCli(argc, argv, Program::kFrontEnd, kOwn);
}
