// The stereo matcher's flags, shared by `stereo`, `stereo frame`, `train ssd` and `detect ssd`:
// every OpenCV StereoBM / StereoSGBM parameter under OpenCV's own name (kebab-cased:
// minDisparity -> --min-disparity, disp12MaxDiff -> --disp12-max-diff, P1 -> --P1), SGBM on the
// colour images, ximgproc's WLS post-filter, the ground fit's switch, and --match-scale (matching
// at a fraction of the image's size, DisparityOptions::match_scale). Each flag is bound to its
// field of StereoOptions (stereo_encoder.h), so `--help` shows the struct's default; the flags that
// name a choice are parsed by FinishStereoFlags.
#ifndef STEREODET_CLI_STEREO_FLAGS_H_
#define STEREODET_CLI_STEREO_FLAGS_H_

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet::cli {

// The text of the flags that name a choice, parsed into StereoOptions by FinishStereoFlags.
struct StereoFlagText {
  std::string method = DisparityMethodName(DisparityOptions().method);
  std::string pre_filter_type;  // empty: the field's default
  std::string mode = SgbmModeName(SemiGlobalOptions().mode);
};

// Adds the flags to `cmd`, bound to `options` and `text`. Returns the flags added, so a caller can
// tell whether the user gave any (`--stereo DIR` and `detect` need that).
std::vector<CLI::Option*> AddStereoFlags(CLI::App* cmd, StereoOptions& options,
                                         StereoFlagText& text);

// The named choices into `options` (throws std::invalid_argument naming the flag), then Check().
void FinishStereoFlags(const StereoFlagText& text, StereoOptions& options);

// The settings of `base` with only the flags given on the command line applied over them, so that
// partial flags change what they name and nothing else (`detect ssd` and `train ssd --resume` start
// from model.json's settings, `--stereo DIR` from stereo.json's). Requires: the command line has
// been parsed; `flags`, `options` and `text` are AddStereoFlags' (`options` and `text` are
// overwritten). Throws as FinishStereoFlags.
StereoOptions ApplyGivenStereoFlags(const std::vector<CLI::Option*>& flags,
                                    const StereoOptions& base, StereoOptions& options,
                                    StereoFlagText& text);

// The names of the flags given, comma-separated ("--uniqueness-ratio, --wls").
std::string GivenFlagNames(const std::vector<CLI::Option*>& flags);

// True when any of `flags` was given on the command line.
bool AnyGiven(const std::vector<CLI::Option*>& flags);

}  // namespace stereodet::cli

#endif  // STEREODET_CLI_STEREO_FLAGS_H_
