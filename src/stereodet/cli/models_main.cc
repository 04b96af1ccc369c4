// stereodet-models: the LibTorch commands (train, detect). `stereodet train|detect ...` runs this
// executable with the same arguments; it also works when called directly (see commands.h).
#include <string_view>
#include <utility>

#include "stereodet/cli/commands.h"

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"train", AddModelsCommand},  // adds train and detect
      {"detect", AddModelsCommand},
  };
  return RunCli(argc, argv, Program::kModels, kOwn);
}
