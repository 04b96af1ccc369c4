// The `stereodet` subcommands. Each area adds its subcommands to the app in its own file; main.cc
// holds the table. A command's callback throws on failure; main() turns that into one clear line on
// stderr and a non-zero exit.
#ifndef STEREODET_CLI_COMMANDS_H_
#define STEREODET_CLI_COMMANDS_H_

#include <CLI/CLI.hpp>

namespace stereodet::cli {

void AddInfoCommand(CLI::App& app);  // info_command.cc (kitti helper)
void AddSynthCommand(CLI::App& app);  // synth_command.cc
void AddEvalCommand(CLI::App& app);   // eval_command.cc (eval, eval sweep, eval compare)
void AddStereoCommand(CLI::App& app);  // stereo_command.cc
#ifdef STEREODET_HAVE_MODELS
void AddModelsCommand(CLI::App& app);  // models_command.cc (train ssd, detect ssd)
#endif

}  // namespace stereodet::cli

#endif  // STEREODET_CLI_COMMANDS_H_
