// stereodet: stereo features, detectors and safety-grade evaluation for KITTI-format data.
// The front end: runs info, eval, report and view itself (no OpenCV, no LibTorch loaded) and hands
// every other command to its sibling executable (see commands.h).
#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  return RunCli(argc, argv, Program::kFrontEnd, FrontEndCommands());
}
