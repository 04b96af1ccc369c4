// FrontEndCommands: what the front end `stereodet` implements itself (commands.h).
#include <span>
#include <string_view>
#include <utility>

#include "stereodet/cli/commands.h"

namespace stereodet::cli {

std::span<const std::pair<std::string_view, AddCommandFn>> FrontEndCommands() {
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"info", AddInfoCommand},     {"eval", AddEvalCommand}, {"calibrate", AddCalibrateCommand},
      {"report", AddReportCommand}, {"view", AddViewCommand},
  };
  return kOwn;
}

}  // namespace stereodet::cli
