// stereodet-vision: the OpenCV commands (synth, stereo). `stereodet synth|stereo ...` runs this
// executable with the same arguments; it also works when called directly (see commands.h).
#include <string_view>
#include <utility>

#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"synth", AddSynthCommand},
      {"stereo", AddStereoCommand},
  };
  return RunCli(argc, argv, Program::kVision, kOwn);
}
