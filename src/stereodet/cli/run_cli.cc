// RunCli: the main() that the front end `stereodet` and its siblings share (see commands.h).
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/util/check.h"
#include "stereodet/util/malloc_tuning.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/version.h"

namespace stereodet::cli {
namespace {

// Why a program may be absent, for the error message.
std::string HowToBuild(Program program) {
  if (program == Program::kModels && !ProgramBuilt(program)) {
    return "it was not built (this build has STEREODET_BUILD_MODELS=OFF or no LibTorch)";
  }
  if (!ProgramBuilt(program)) return "it was not built (its modules are not in this build)";
  return "build it (cmake --build BUILD_DIR --target " + std::string(ProgramName(program)) +
         ") and keep it beside stereodet";
}

// Replaces this process with `command`'s program from this executable's folder, passing `argv`
// (argv[0] as the user typed it, so usage lines and messages name `stereodet`). Returns only by
// throwing, when the program cannot be run.
void ExecOwner(const Command& command, char** argv) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) {
    throw std::runtime_error("cannot find this executable's folder (/proc/self/exe: " +
                             error.message() + ") to run `" + std::string(command.name) + "`");
  }
  const std::filesystem::path owner = self.parent_path() / ProgramName(command.program);
  std::fflush(nullptr);
  ::execv(owner.c_str(), argv);
  const int exec_errno = errno;
  if (exec_errno == ENOENT) {
    throw std::runtime_error("the `" + std::string(command.name) + "` command is in " +
                             owner.string() +
                             ", which is not there: " + HowToBuild(command.program));
  }
  throw std::runtime_error("cannot run " + owner.string() + " for `" + std::string(command.name) +
                           "`: " + std::strerror(exec_errno));
}

const Command* FindCommand(std::string_view name) {
  for (const Command& command : CommandTable()) {
    if (command.name == name) return &command;
  }
  return nullptr;
}

// "unknown command 'x' (commands: synth, stereo, ...); ...", the word quoted printable and short.
std::string UnknownCommandMessage(std::string_view name) {
  constexpr size_t kMaxShown = 40;
  std::string quoted;
  for (size_t i = 0; i < name.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    quoted += c >= 0x20 && c < 0x7f ? std::string(1, static_cast<char>(c)) : "?";
  }
  if (name.size() > kMaxShown) quoted += "...";
  std::string names;
  for (const Command& command : CommandTable()) {
    names += (names.empty() ? "" : ", ") + std::string(command.name);
  }
  return "unknown command '" + quoted + "' (commands: " + names + "); run `stereodet --help`";
}

AddCommandFn FindOwn(std::span<const std::pair<std::string_view, AddCommandFn>> own,
                     std::string_view name) {
  for (const auto& [own_name, add] : own) {
    if (own_name == name) return add;
  }
  return nullptr;
}

// A stand-in for a command of another executable: listed by --help with the table's description,
// it parses nothing itself (no --help flag, every argument kept) and hands over to the owner.
void AddStandIn(CLI::App& app, const Command& command, const char* argv0) {
  std::string description(command.description);
  if (!ProgramBuilt(command.program)) description += " [not built]";
  CLI::App* stand_in = app.add_subcommand(std::string(command.name), description);
  stand_in->set_help_flag();
  stand_in->prefix_command();
  stand_in->allow_extras();
  stand_in->callback([stand_in, &command, argv0] {
    std::vector<std::string> args = {argv0, std::string(command.name)};
    for (const std::string& arg : stand_in->remaining()) args.push_back(arg);
    std::vector<char*> c_args;
    for (std::string& arg : args) c_args.push_back(arg.data());
    c_args.push_back(nullptr);
    ExecOwner(command, c_args.data());
  });
}

// CLI11's help with each exclusion listed once, on the side that names the most options: `--stereo`
// says "Excludes: --block-size --num-disparities ...", and those options no longer each repeat
// "Excludes: --stereo" (a pair of equals is listed on the option declared first).
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_opts(const CLI::Option* option) const override {
    std::string out = CLI::Formatter::make_option_opts(option);
    const std::string label = " " + get_label("Excludes") + ":";
    if (const size_t at = out.rfind(label); at != std::string::npos) out.erase(at);
    std::string listed;
    for (const CLI::Option* other : option->get_excludes()) {
      if (ListsExclusion(option, other)) listed += " " + other->get_name();
    }
    if (!listed.empty()) out += label + listed;
    return out;
  }

 private:
  static bool ListsExclusion(const CLI::Option* option, const CLI::Option* other) {
    const size_t mine = option->get_excludes().size();
    const size_t theirs = other->get_excludes().size();
    if (mine != theirs) return mine > theirs;
    return option->get_name() < other->get_name();
  }
};

// The Levenshtein distance between two option names (insertions, deletions, substitutions).
size_t EditDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// "Did you mean --X?" lines for the unexpected long options of a failed parse: the nearest option
// of the command the line named (the deepest parsed subcommand) or of the commands above it, when
// it is within a third of the word's length (at least 2 edits). Empty when nothing is near.
std::string NearestOptionHints(const CLI::App& app) {
  const CLI::App* command = &app;
  while (!command->get_subcommands().empty()) command = command->get_subcommands().front();
  std::vector<std::string> names;
  for (const CLI::App* level = command; level != nullptr; level = level->get_parent()) {
    for (const CLI::Option* option : level->get_options()) {
      for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    }
  }
  std::string hints;
  for (const std::string& arg : app.remaining(/*recurse=*/true)) {
    if (!arg.starts_with("--") || arg.size() < 3) continue;
    const std::string word = arg.substr(0, arg.find('='));
    const std::string* best = nullptr;
    size_t best_distance = std::max<size_t>(2, (word.size() - 2) / 3) + 1;
    for (const std::string& name : names) {
      const size_t distance = EditDistance(word, name);
      if (distance < best_distance) best_distance = distance, best = &name;
    }
    if (best != nullptr && best_distance > 0) hints += word + ": did you mean " + *best + "?\n";
  }
  return hints;
}

// `--debug` on `app` and on each of its commands and their subcommands (not on the stand-ins, whose
// arguments go to another executable that declares it itself). The flag only has to be accepted:
// DebugRequested reads it from argv.
void AddDebugFlags(CLI::App& app) {
  static const std::string kHelp =
      "error messages keep the source file, line and condition of the failed check (for bug "
      "reports; the environment variable STEREODET_DEBUG=1 does the same)";
  if (app.get_option_no_throw("--debug") == nullptr) app.add_flag("--debug", kHelp);
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    if (!sub->get_prefix_command()) AddDebugFlags(*sub);
  }
}

// RunCli, and with !may_exec RunCommandInProcess: another executable's command is then refused
// instead of execv()ed over the calling process.
int RunCliIn(int argc, char** argv, Program self,
             std::span<const std::pair<std::string_view, AddCommandFn>> own, bool may_exec) {
  CLI::App app{std::string("stereodet ") + StereodetVersion() +
               ": stereo features, detectors and safety-grade evaluation on KITTI-format data.\n"
               "Run `stereodet COMMAND --help` for the options of a command."};
  app.set_version_flag("--version", std::string("stereodet ") + StereodetVersion());
  app.require_subcommand(1);
  app.fallthrough();
  app.formatter(std::make_shared<HelpFormatter>());  // subcommands added below inherit it
  // --debug is read from argv before parsing (errors can come before CLI11 would set a flag);
  // every command declares it (AddDebugFlags) so that CLI11 accepts it and --help lists it.
  // Set for this call only, and only when nothing else (the environment, an earlier setting) has
  // debug messages on already: RunCommandInProcess's callers keep their own setting.
  struct DebugForThisCall {
    bool set_here;
    ~DebugForThisCall() {
      if (set_here) SetDebugMessages(false);
    }
  } debug_for_this_call{DebugRequested(argc, argv) && !DebugMessages()};
  if (debug_for_this_call.set_here) SetDebugMessages(true);

  try {
    // `stereodet [FLAGS] NAME ...` with NAME another executable's command: hand over the untouched
    // argv before parsing anything. The top level takes only flags (--help, --version), so the
    // first argument without a leading '-' is the command, and the owner, whose top level is the
    // same, parses argv exactly as a single binary would (`stereodet --help synth` included).
    for (int i = 1; i < argc; ++i) {
      if (argv[i][0] == '-') continue;
      const Command* command = FindCommand(argv[i]);
      // CLI11 would say only "A subcommand is required", naming neither the word nor the commands.
      if (command == nullptr) throw std::invalid_argument(UnknownCommandMessage(argv[i]));
      if (command->program != self) {
        if (!may_exec) {
          throw std::runtime_error("`" + std::string(command->name) + "` runs in " +
                                   ProgramName(command->program) +
                                   ", not in this process; run that executable (or the stereodet "
                                   "front end) instead");
        }
        ExecOwner(*command, argv);
      }
      break;
    }
    std::set<AddCommandFn> added;
    for (const Command& command : CommandTable()) {
      if (command.program != self) {
        AddStandIn(app, command, argv[0]);
      } else if (AddCommandFn add = FindOwn(own, command.name); add == nullptr) {
        throw std::logic_error(std::string(ProgramName(self)) + " does not implement `" +
                               std::string(command.name) + "` that the command table gives it");
      } else if (added.insert(add).second) {
        add(app);
      }
    }
    AddDebugFlags(app);
    app.parse(argc, argv);
  } catch (const CLI::ExtrasError& e) {
    // CLI11's message and exit code, with the nearest option of the command when one is close.
    std::fprintf(stderr, "%s\n%sRun with --help for more information.\n", e.what(),
                 NearestOptionHints(app).c_str());
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    return app.exit(e);  // usage errors: message + hint, CLI11's exit codes (non-zero)
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stereodet: error: %s\n", UserMessage(e).c_str());
    return 1;
  }
  return 0;
}

}  // namespace

bool DebugRequested(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--") == 0) return false;
    if (std::strcmp(argv[i], "--debug") == 0) return true;
  }
  return false;
}

int RunCli(int argc, char** argv, Program self,
           std::span<const std::pair<std::string_view, AddCommandFn>> own) {
  // An executable's own process: its allocator policy is ours to set (RunCommandInProcess, which
  // runs inside someone else's process, leaves it alone).
  KeepLargeBuffersInHeap();
  return RunCliIn(argc, argv, self, own, /*may_exec=*/true);
}

namespace {

// RunCommandInProcess's command line on this thread (the arguments, NUL-separated as
// /proc/self/cmdline holds them), or nothing outside such a call.
thread_local std::optional<std::string> in_process_command_line;

}  // namespace

std::string ProcessCommandLine() {
  std::string raw;
  if (in_process_command_line) {
    raw = *in_process_command_line;
  } else {
    // /proc files report size 0, so read to the end rather than by size.
    std::ifstream in("/proc/self/cmdline", std::ios::binary);
    if (!in) return {};
    raw.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  std::string out;
  for (std::string_view arg : Split(raw, '\0')) {
    if (arg.empty()) continue;
    if (!out.empty()) out += ' ';
    if (arg.find_first_of(" \t'\"") == std::string_view::npos) {
      out += arg;
    } else {
      out += '\'';
      for (const char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

int RunCommandInProcess(const std::vector<std::string>& args, Program self,
                        std::span<const std::pair<std::string_view, AddCommandFn>> own) {
  std::vector<std::string> argv_text = {"stereodet"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::string joined;
  for (const std::string& arg : argv_text) joined += arg + '\0';
  std::vector<char*> argv;
  for (std::string& arg : argv_text) argv.push_back(arg.data());
  argv.push_back(nullptr);
  in_process_command_line = joined;
  struct Reset {
    ~Reset() { in_process_command_line.reset(); }
  } reset;
  const int code = RunCliIn(static_cast<int>(argv.size()) - 1, argv.data(), self, own,
                            /*may_exec=*/false);
  std::fflush(nullptr);
  return code;
}

}  // namespace stereodet::cli
