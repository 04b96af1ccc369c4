// stereodet-vision: the OpenCV commands (synth, stereo). `stereodet synth|stereo ...` runs this
// executable with the same arguments; it also works when called directly (see commands.h).
#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  return RunCli(argc, argv, Program::kVision, VisionCommands());
}
