#include "stereodet/cli/stereo_flags.h"

#include <fmt/format.h>

#include "stereodet/util/check.h"

namespace stereodet::cli {

std::vector<CLI::Option*> AddStereoFlags(CLI::App* cmd, StereoOptions& options,
                                         StereoFlagText& text) {
  DisparityOptions& d = options.disparity;
  std::vector<CLI::Option*> flags;
  auto add = [&flags](CLI::Option* option) {
    flags.push_back(option);
    return option;
  };
  add(cmd->add_option("--method", text.method,
                      "disparity: bm (OpenCV StereoBM) or sgbm (StereoSGBM)"))
      ->check(CLI::IsMember({"bm", "sgbm"}))
      ->capture_default_str();
  add(cmd->add_option("--num-disparities", d.num_disparities,
                      "numDisparities: search range, px, a multiple of 16"))
      ->capture_default_str();
  // One flag for the window of both matchers, whose defaults differ.
  add(cmd->add_option_function<int>(
      "--block-size",
      [&d](const int& block_size) {
        d.bm.block_size = block_size;
        d.sgbm.block_size = block_size;
      },
      fmt::format("blockSize: matching window side, px, odd (default BM {}, SGBM {})",
                  d.bm.block_size, d.sgbm.block_size)));
  add(cmd->add_option("--min-disparity", d.min_disparity, "minDisparity: smallest disparity, px"))
      ->capture_default_str();
  add(cmd->add_option("--match-scale", d.match_scale,
                      "match at this fraction of the image's size, 0.1..1 (0.5 = half: the pair "
                      "resized with INTER_AREA, disparities, block and speckle settings scaled to "
                      "it; docs/stereo.md)"))
      ->capture_default_str();
  add(cmd->add_option("--uniqueness-ratio", d.uniqueness_ratio,
                      "uniquenessRatio: the best cost beats the second by this percent"))
      ->capture_default_str();
  add(cmd->add_option("--speckle-window-size", d.speckle_window_px,
                      "speckleWindowSize: smaller regions are removed, px (0 = off)"))
      ->capture_default_str();
  add(cmd->add_option("--speckle-range", d.speckle_range_px,
                      "speckleRange: disparity variation within a region, px"))
      ->capture_default_str();
  add(cmd->add_option("--disp12-max-diff", d.left_right_max_diff_px,
                      "disp12MaxDiff: left-right check, px (BM: -1 = off)"))
      ->capture_default_str();
  // preFilterCap exists in both matchers, with different defaults and ranges.
  add(cmd->add_option_function<int>(
      "--pre-filter-cap",
      [&d](const int& cap) {
        d.bm.prefilter_cap = cap;
        d.sgbm.prefilter_cap = cap;
      },
      fmt::format("preFilterCap (default BM {}, 1..63; SGBM {}, 1..1023)", d.bm.prefilter_cap,
                  d.sgbm.prefilter_cap)));
  add(cmd->add_option("--pre-filter-size", d.bm.prefilter_size,
                      "BM preFilterSize: odd, 5..255, normalized-response pre-filter only"))
      ->capture_default_str();
  add(cmd->add_option("--pre-filter-type", text.pre_filter_type,
                      fmt::format("BM preFilterType: xsobel or normalized-response (default {})",
                                  d.bm.xsobel_prefilter ? "xsobel" : "normalized-response")))
      ->check(CLI::IsMember({"xsobel", "normalized-response"}));
  add(cmd->add_option("--texture-threshold", d.bm.texture_threshold,
                      "BM textureThreshold: windows with less texture are invalid"))
      ->capture_default_str();
  add(cmd->add_option_function<int>(
      "--P1", [&d](const int& p1) { d.sgbm.p1 = p1; },
      "SGBM P1 itself (default: --P1-per-pixel x channels x blockSize^2)"));
  add(cmd->add_option_function<int>(
      "--P2", [&d](const int& p2) { d.sgbm.p2 = p2; },
      "SGBM P2 itself, > P1 (default: --P2-per-pixel x channels x blockSize^2)"));
  add(cmd->add_option("--P1-per-pixel", d.sgbm.p1_per_pixel,
                      "SGBM: P1 = this x channels x blockSize^2 unless --P1"))
      ->capture_default_str();
  add(cmd->add_option("--P2-per-pixel", d.sgbm.p2_per_pixel,
                      "SGBM: P2 = this x channels x blockSize^2 unless --P2"))
      ->capture_default_str();
  add(cmd->add_option("--mode", text.mode, "SGBM mode: sgbm, hh, sgbm3way or hh4"))
      ->check(CLI::IsMember({"sgbm", "hh", "sgbm3way", "hh4"}))
      ->capture_default_str();
  add(cmd->add_flag("--colour", d.sgbm.colour,
                    "SGBM: match the BGR images as OpenCV takes them, not their grey versions"));
  add(cmd->add_flag("--wls", d.wls.enabled,
                    "post-filter the disparity with OpenCV ximgproc's DisparityWLSFilter (dense)"));
  add(cmd->add_option("--wls-lambda", d.wls.lambda, "WLS lambda: smoothing strength"))
      ->capture_default_str();
  add(cmd->add_option("--wls-sigma-color", d.wls.sigma_color,
                      "WLS sigmaColor: sensitivity to the image's edges"))
      ->capture_default_str();
  add(cmd->add_option("--wls-lrc-thresh", d.wls.lrc_threshold,
                      "WLS LRCthresh: left-right check threshold, 1/16 px"))
      ->capture_default_str();
  add(cmd->add_option("--wls-depth-discontinuity-radius", d.wls.depth_discontinuity_radius,
                      "WLS DepthDiscontinuityRadius, px"))
      ->capture_default_str();
  add(cmd->add_option("--ground-warn-tilt", options.ground.warn_tilt_deg,
                      "warn when an accepted ground fit is tilted more than this, degrees"))
      ->capture_default_str();
  add(cmd->add_option("--ground-warn-height", options.ground.warn_camera_height_m,
                      "warn when a ground fit's camera height is this far from nominal, m"))
      ->capture_default_str();
  add(cmd->add_flag("--ground-prior", options.ground.suspect_uses_prior,
                    "use the nominal plane (the prior) where a fit is beyond that tolerance"));
  add(cmd->add_flag(
      "--no-ground-fit", [&options](int64_t) { options.ground.enabled = false; },
      "use the nominal ground plane (camera 1.65 m up) instead of fitting it"));
  return flags;
}

void FinishStereoFlags(const StereoFlagText& text, StereoOptions& options) {
  const auto method = ParseDisparityMethod(text.method);
  STEREODET_CHECK(method.has_value()) << "--method: unknown '" << text.method << "' (bm, sgbm)";
  options.disparity.method = *method;
  const auto mode = ParseSgbmMode(text.mode);
  STEREODET_CHECK(mode.has_value())
      << "--mode: unknown '" << text.mode << "' (sgbm, hh, sgbm3way, hh4)";
  options.disparity.sgbm.mode = *mode;
  if (!text.pre_filter_type.empty()) {
    STEREODET_CHECK(text.pre_filter_type == "xsobel" ||
                    text.pre_filter_type == "normalized-response")
        << "--pre-filter-type: unknown '" << text.pre_filter_type
        << "' (xsobel, normalized-response)";
    options.disparity.bm.xsobel_prefilter = text.pre_filter_type == "xsobel";
  }
  options.Check();
}

StereoOptions ApplyGivenStereoFlags(const std::vector<CLI::Option*>& flags,
                                    const StereoOptions& base, StereoOptions& options,
                                    StereoFlagText& text) {
  options = base;
  text = StereoFlagText();
  text.method = DisparityMethodName(base.disparity.method);
  text.mode = SgbmModeName(base.disparity.sgbm.mode);
  // Each given flag's callback stores its parsed value again, now over `base`.
  for (CLI::Option* flag : flags) {
    if (flag->count() > 0) flag->run_callback();
  }
  FinishStereoFlags(text, options);
  return options;
}

std::string GivenFlagNames(const std::vector<CLI::Option*>& flags) {
  std::string names;
  for (const CLI::Option* flag : flags) {
    if (flag->count() == 0) continue;
    if (!names.empty()) names += ", ";
    names += flag->get_name();
  }
  return names;
}

bool AnyGiven(const std::vector<CLI::Option*>& flags) {
  for (const CLI::Option* flag : flags) {
    if (flag->count() > 0) return true;
  }
  return false;
}

}  // namespace stereodet::cli
