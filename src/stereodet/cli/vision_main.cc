// stereodet-vision: the OpenCV commands (synth, stereo). `stereodet synth|stereo ...` runs this
// executable with the same arguments; it also works when called directly (see commands.h).
#include <opencv2/core/utils/logger.hpp>

#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  // OpenCV's own warnings (a PNG it cannot decode, a codec's notes) would print before our error
  // line, which names the file and says what is wrong: ours suffices.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return RunCli(argc, argv, Program::kVision, VisionCommands());
}
