// The `stereodet` commands and the executables that hold them.
//
// `stereodet` is a git-style front end: it runs the commands that need neither OpenCV nor LibTorch
// (info, eval, report, view) itself and hands the others to a sibling executable in its own folder,
// so that a command loads only the libraries it uses:
//   stereodet         info, eval, report, view  (util, geometry, kitti, eval, report)
//   stereodet-vision  synth, stereo         (+ OpenCV)
//   stereodet-models  train, detect, run    (+ OpenCV, LibTorch; only with STEREODET_BUILD_MODELS)
// CommandTable() below is the one list of commands (name, owner, description) that every executable
// shares; each executable's main() passes its own Add*Command functions to RunCli(), which adds the
// others as stand-ins that execv() their owner with the same argv, so usage, messages and exit
// codes are those of the owner. Each area adds its subcommands in its own *_command.cc; a command's
// callback throws on failure and RunCli turns that into one clear line on stderr and exit 1.
#ifndef STEREODET_CLI_COMMANDS_H_
#define STEREODET_CLI_COMMANDS_H_

#include <CLI/CLI.hpp>
#include <charconv>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stereodet/util/shard.h"

namespace stereodet::cli {

// The executables of the CLI, all built into the same folder (build/bin/).
enum class Program { kFrontEnd, kVision, kModels };

// The file name of `program` ("stereodet", "stereodet-vision", "stereodet-models").
const char* ProgramName(Program program);
std::optional<Program> ParseProgram(std::string_view text);

// Whether this build configured `program` (kModels needs STEREODET_BUILD_MODELS=ON and LibTorch).
bool ProgramBuilt(Program program);

struct Command {
  std::string_view name;         // the first argument: `stereodet NAME ...`
  Program program;               // the executable that implements it
  std::string_view description;  // shown by `stereodet --help` and `stereodet NAME --help`
};

// Every top-level command, in the order `stereodet --help` lists them.
std::span<const Command> CommandTable();

// The description of the command `name` in CommandTable(). Requires: `name` is in the table
// (throws std::logic_error otherwise).
std::string CommandDescription(std::string_view name);

// Adds one area's subcommands (each *_command.cc defines one of these).
using AddCommandFn = void (*)(CLI::App&);
void AddInfoCommand(CLI::App& app);       // info_command.cc (kitti helper)
void AddEvalCommand(CLI::App& app);       // eval_command.cc (eval, eval sweep, eval compare)
void AddCalibrateCommand(CLI::App& app);  // eval_command.cc (calibrate --fit)
void AddReportCommand(CLI::App& app);     // report_command.cc (figures and the HTML report)
void AddViewCommand(CLI::App& app);       // report_command.cc (frame views)
void AddSynthCommand(CLI::App& app);      // synth_command.cc
void AddStereoCommand(CLI::App& app);     // stereo_command.cc
void AddModelsCommand(CLI::App& app);     // models_command.cc (train ssd, detect ssd)
void AddRunCommand(CLI::App& app);        // run_command.cc (stereodet run: streams, latency)

// The whole main() of the executable `self`: `own` maps each command that `self` implements to the
// function adding it (a function named twice, as train and detect, is called once). A command of
// another executable is dispatched with execv() to that executable beside /proc/self/exe, with
// argv unchanged; if it is missing, one line says so and the exit code is 1. Returns the exit
// code: 0, CLI11's code for a usage error, or 1 for an error thrown by a command.
// Adds `--shard K/N` to `cmd`, parsed into `shard` (util/shard.h; a bad text is a usage error that
// names the flag). Shared by synth, stereo, detect and eval (docs/scale.md).
inline CLI::Option* AddShardOption(CLI::App* cmd, Shard* shard) {
  return cmd
      ->add_option_function<std::string>(
          "--shard",
          [shard](const std::string& text) {
            const std::optional<Shard> parsed = ParseShard(text);
            if (!parsed) {
              throw CLI::ValidationError(
                  "--shard", "expected K/N with 0 <= K < N <= 1000000, got '" + text + "'");
            }
            *shard = *parsed;
          },
          "only shard K/N (K = 0..N-1) of the frames: the K-th of N contiguous ranges of the frame "
          "list (docs/scale.md)")
      ->default_str(ShardName(*shard));
}

// Adds `--seed N` to `cmd`, parsed into `seed` as a whole number in [0, 2^64 - 1]: a larger one is
// a usage error naming the flag (CLI11's own conversion saturates it to 2^64 - 1, silently the seed
// of another data set or training).
inline CLI::Option* AddSeedOption(CLI::App* cmd, uint64_t* seed, const std::string& description) {
  return cmd
      ->add_option_function<std::string>(
          "--seed",
          [seed](const std::string& text) {
            uint64_t value = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
            if (text.empty() || ec != std::errc() || end != text.data() + text.size()) {
              throw CLI::ValidationError(
                  "--seed",
                  "expected a whole number from 0 to 18446744073709551615, got '" + text + "'");
            }
            *seed = value;
          },
          description)
      ->default_str(std::to_string(*seed));
}

// The command line of this process (/proc/self/cmdline), arguments joined by spaces, those with
// spaces or quotes in single quotes, for provenance records. Empty where /proc is not there. Inside
// RunCommandInProcess on this thread: that call's "stereodet ARGS...", quoted the same way.
std::string ProcessCommandLine();

// Whether the command line asks for debug messages: an argument "--debug" before any "--". RunCli
// then keeps the source tags of failed checks in its error line (UserMessage, util/check.h).
bool DebugRequested(int argc, char** argv);

int RunCli(int argc, char** argv, Program self,
           std::span<const std::pair<std::string_view, AddCommandFn>> own);

// The commands the front end `stereodet` implements itself (info, eval, report, view), with their
// Add*Command functions: its main()'s list, and the Python module's (frontend_commands.cc).
std::span<const std::pair<std::string_view, AddCommandFn>> FrontEndCommands();

// The commands of stereodet-vision (synth, stereo): its main()'s list, and the stereodet._stereo
// module's in-process tasks (vision_commands.cc).
std::span<const std::pair<std::string_view, AddCommandFn>> VisionCommands();

// `stereodet ARGS...` (args without the program name: {"eval", "--gt", "DIR", ...}) run in this
// process, for callers that are not a main() (the Python module's in-process tasks, docs/scale.md):
// RunCli's parsing, messages and exit codes, but a command of another executable is refused (an
// error line and exit 1) instead of replacing the calling process with execv(), and the command
// line recorded in run manifests (ProcessCommandLine, on this thread) is "stereodet ARGS...", not
// the caller's. One call at a time per thread; commands keep no state between calls.
int RunCommandInProcess(const std::vector<std::string>& args, Program self,
                        std::span<const std::pair<std::string_view, AddCommandFn>> own);

}  // namespace stereodet::cli

#endif  // STEREODET_CLI_COMMANDS_H_
