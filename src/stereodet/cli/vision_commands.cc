// VisionCommands: what stereodet-vision implements (commands.h).
#include <span>
#include <string_view>
#include <utility>

#include "stereodet/cli/commands.h"

namespace stereodet::cli {

std::span<const std::pair<std::string_view, AddCommandFn>> VisionCommands() {
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"synth", AddSynthCommand},
      {"stereo", AddStereoCommand},
  };
  return kOwn;
}

}  // namespace stereodet::cli
