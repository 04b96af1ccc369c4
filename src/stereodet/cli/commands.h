// The `stereodet` subcommands. Each area adds its subcommands to the app in its own file; main.cc
// holds the table. A command's callback throws on failure; main() turns that into one clear line on
// stderr and a non-zero exit.
#ifndef STEREODET_CLI_COMMANDS_H_
#define STEREODET_CLI_COMMANDS_H_

#include <CLI/CLI.hpp>

namespace stereodet::cli {

void AddSynthCommand(CLI::App& app);  // synth_command.cc
void AddInfoCommand(CLI::App& app);  // info_command.cc
void AddEvalCommand(CLI::App& app);  // eval_command.cc (eval, eval sweep, eval compare)

}  // namespace stereodet::cli

#endif  // STEREODET_CLI_COMMANDS_H_
