// stereodet-models: the LibTorch commands (train, detect, run). `stereodet train|detect ...` runs
// this executable with the same arguments; it also works when called directly (see commands.h).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <opencv2/core/utils/logger.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/models/detector.h"
#include "stereodet/util/check.h"

namespace {

// `detect --model DIR ...` without a family word: the family model.json names is put after
// `detect`, so the family's own command (flags, help, messages) runs. Any other argv is returned
// as it is; a model.json that cannot be read is left to the family command to report.
std::vector<std::string> WithModelFamily(int argc, char** argv) {
  std::vector<std::string> args(argv, argv + argc);
  size_t detect = 1;
  while (detect < args.size() && !args[detect].empty() && args[detect][0] == '-') ++detect;
  if (detect + 1 >= args.size() || args[detect] != "detect" || args[detect + 1].empty() ||
      args[detect + 1][0] != '-') {
    return args;
  }
  std::string model;
  for (size_t i = detect + 1; i < args.size(); ++i) {
    if (args[i] == "--model" && i + 1 < args.size()) model = args[i + 1];
    if (args[i].rfind("--model=", 0) == 0) model = args[i].substr(8);
  }
  if (model.empty()) return args;
  try {
    args.insert(args.begin() + static_cast<std::ptrdiff_t>(detect) + 1,
                stereodet::ModelFamily(model));
  } catch (const std::exception& e) {
    if (stereodet::cli::DebugRequested(argc, argv)) stereodet::SetDebugMessages(true);
    std::fprintf(stderr, "stereodet: error: detect --model: %s\n",
                 stereodet::UserMessage(e).c_str());
    std::exit(1);
  }
  return args;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace stereodet::cli;
  static constexpr std::pair<std::string_view, AddCommandFn> kOwn[] = {
      {"train", AddModelsCommand},  // adds train and detect
      {"detect", AddModelsCommand},
      {"run", AddRunCommand},
  };
  // OpenCV's own warnings would print before our error line, which names the file: ours suffices.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  std::vector<std::string> args = WithModelFamily(argc, argv);
  std::vector<char*> c_args;
  for (std::string& arg : args) c_args.push_back(arg.data());
  c_args.push_back(nullptr);
  return RunCli(static_cast<int>(args.size()), c_args.data(), Program::kModels, kOwn);
}
