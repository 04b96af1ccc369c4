// stereodet: stereo features, detectors and safety-grade evaluation for KITTI-format data.
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>

#include "stereodet/cli/commands.h"
#include "stereodet/util/check.h"

#ifndef STEREODET_VERSION
#define STEREODET_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{"stereodet " STEREODET_VERSION
               ": stereo features, detectors and safety-grade evaluation on KITTI-format data.\n"
               "Run `stereodet COMMAND --help` for the options of a command."};
  app.set_version_flag("--version", std::string("stereodet ") + STEREODET_VERSION);
  app.require_subcommand(1);
  app.fallthrough();

  // The subcommand table, in the order a user meets them.
  stereodet::cli::AddSynthCommand(app);  // synth
  stereodet::cli::AddStereoCommand(app);  // stereo
  stereodet::cli::AddInfoCommand(app);  // kitti helper
  stereodet::cli::AddEvalCommand(app);  // eval
#ifdef STEREODET_HAVE_MODELS
  stereodet::cli::AddModelsCommand(app);  // train ssd, detect ssd
#endif

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);  // usage errors: message + hint, exit code 2 (CLI11's codes)
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stereodet: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
