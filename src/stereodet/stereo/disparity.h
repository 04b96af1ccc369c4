// Disparity from a rectified stereo pair (KITTI cameras 2 and 3) with OpenCV's block matcher
// (StereoBM, the default, as in the paper) or semi-global matcher (StereoSGBM), and the KITTI
// stereo-benchmark file format for disparity maps.
//
// Disparity maps are CV_32FC1 images in the left image's frame, in pixels (u_left - u_right,
// sub-pixel with OpenCV's 1/16 px resolution). Pixels without a match hold kInvalidDisparity (-1);
// a disparity of 0 (a point at infinity) is never produced for a valid pixel, so no invalid pixel
// can read as "0 m".
#ifndef STEREODET_STEREO_DISPARITY_H_
#define STEREODET_STEREO_DISPARITY_H_

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace stereodet {

// The value of a pixel with no disparity. Test validity with IsValidDisparity, not equality.
inline constexpr float kInvalidDisparity = -1.0f;
// True for a usable disparity (> 0). False for kInvalidDisparity, 0, negatives and NaN.
inline bool IsValidDisparity(float disparity_px) { return disparity_px > 0.0f; }

enum class DisparityMethod { kBlockMatching, kSemiGlobal };
const char* DisparityMethodName(DisparityMethod method);  // "bm", "sgbm"
std::optional<DisparityMethod> ParseDisparityMethod(std::string_view text);

// StereoBM settings. Defaults measured on KITTI-like frames and the Middlebury Aloe pair
// (docs/stereo.md).
struct BlockMatchingOptions {
  int block_size = 11;           // odd, 5..255: side of the square SAD window, pixels
  bool xsobel_prefilter = true;  // x-Sobel pre-filter (true) or normalized response (false)
  int prefilter_size = 9;        // odd, 5..255; used by the normalized-response pre-filter only
  int prefilter_cap = 31;        // 1..63: clips the pre-filtered intensities
  int texture_threshold = 10;    // >= 0: windows with less texture (sum |dI/dx|) are invalid
  void Check() const;            // throws std::invalid_argument
};

// StereoSGBM's `mode`: MODE_SGBM (5 paths, the default), MODE_HH (8 paths, full-size buffers, ~2x
// slower), MODE_SGBM_3WAY (3 paths, fastest), MODE_HH4 (4 paths).
enum class SgbmMode { kSgbm, kHh, kSgbm3Way, kHh4 };
const char* SgbmModeName(SgbmMode mode);  // "sgbm", "hh", "sgbm3way", "hh4"
std::optional<SgbmMode> ParseSgbmMode(std::string_view text);

// StereoSGBM settings.
struct SemiGlobalOptions {
  int block_size = 5;  // odd, 1..255: matching window side, pixels
  // Smoothness penalties: for +-1 px changes P1 = p1_per_pixel * channels * block^2 and for larger
  // ones P2 = p2_per_pixel * channels * block^2 (OpenCV's rule; channels = 3 with `colour`), unless
  // `p1` / `p2` give OpenCV's P1 / P2 themselves. Requires 0 < P1 < P2.
  int p1_per_pixel = 8;
  int p2_per_pixel = 32;
  std::optional<int> p1;   // OpenCV's P1 itself (--P1), replacing the per-pixel rule
  std::optional<int> p2;   // OpenCV's P2 itself (--P2)
  int prefilter_cap = 63;  // 1..1023: clips the x-derivative pre-filter (OpenCV's preFilterCap)
  SgbmMode mode = SgbmMode::kSgbm;
  // Match the BGR images as OpenCV takes them (3-channel costs) instead of their grey versions.
  bool colour = false;
  int Channels() const { return colour ? 3 : 1; }
  int P1() const { return p1 ? *p1 : p1_per_pixel * Channels() * block_size * block_size; }
  int P2() const { return p2 ? *p2 : p2_per_pixel * Channels() * block_size * block_size; }
  void Check() const;
};

// OpenCV ximgproc's weighted-least-squares post-filter (DisparityWLSFilter): the left disparity is
// smoothed edge-aware, guided by the left image, with a right matcher's disparity for the
// left-right confidence. It fills the matcher's holes, so the map becomes dense. Off by default.
struct WlsFilterOptions {
  bool enabled = false;
  double lambda = 8000.0;    // > 0: regularization strength (OpenCV's lambda; 8000 typical)
  double sigma_color = 1.5;  // > 0: sensitivity to the guide's edges (OpenCV's sigmaColor)
  int lrc_threshold = 24;    // >= 0: left-right check threshold in 1/16 px (OpenCV's LRCthresh)
  // >= 0: radius around depth discontinuities with low confidence, px (OpenCV's
  // DepthDiscontinuityRadius; OpenCV sets it from the matcher's window, which is this default for
  // a block of 11: ceil(0.33 * 11)).
  int depth_discontinuity_radius = 4;
  void Check() const;
};

struct DisparityOptions {
  DisparityMethod method = DisparityMethod::kBlockMatching;
  // > 0, multiple of 16: search range [min, min + num) pixels. 128 px is a depth of
  // f b / 128 = 3.0 m on KITTI; the left-most (min + num - 1) columns get no disparity.
  int num_disparities = 128;
  int min_disparity = 0;        // pixels
  int uniqueness_ratio = 15;    // 0..100: the best cost must beat the second best by this percent
  int speckle_window_px = 100;  // >= 0: regions of fewer pixels than this are removed (0 = off)
  int speckle_range_px = 2;     // >= 0: disparity variation within one speckle region, pixels
  // Left-right consistency: pixels whose left and right disparities differ by more than this many
  // pixels are invalid. OpenCV's disp12MaxDiff: for BM a cost-based check, disabled by < 0; SGBM
  // computes the right disparity itself and always checks (OpenCV treats values <= 0 as 1).
  int left_right_max_diff_px = 1;
  BlockMatchingOptions bm;
  SemiGlobalOptions sgbm;
  WlsFilterOptions wls;
  // Match at this fraction of the image's size, in [0.1, 1] (--match-scale; 1 = full resolution,
  // what every setting above means; 0.5 = half). The pair is resized with INTER_AREA to
  // MatchSize() and matched with AtMatchScale()'s settings, so the disparity comes out in pixels
  // of the match-scale image (about match_scale x the full-resolution disparity). Matching costs
  // roughly match_scale^3 of the full-resolution matcher (pixels x disparities): 1/8 at 0.5.
  // Default 1, and 1 for a stereo.json / model.json recorded without this key.
  double match_scale = 1.0;
  void Check() const;  // throws std::invalid_argument, also for a bad setting of the chosen method
  // The size the matcher sees for an image of `image` px: (round(w s), round(h s)), s = match_scale
  // (the image's own size at 1).
  cv::Size MatchSize(cv::Size image) const;
  // The settings that mean at MatchSize() what these mean at full resolution (match_scale 1 in the
  // result; *this unchanged at 1). With s = match_scale, odd(x) = the odd integer in [x - 1, x +
  // 1):
  //   num_disparities   16 ceil(num s / 16), at least 16 (the same nearest depth, rounded up)
  //   min_disparity     floor(min s)
  //   bm.block_size     max(5, odd(block s))     bm.prefilter_size  max(5, odd(size s))
  //   sgbm.block_size   odd(block s); SGBM's per-pixel P1/P2 rule follows it (--P1/--P2 kept)
  //   speckle_window_px round(window s^2) (an area)
  //   speckle_range_px  round(range s), at least 1 where it was (a disparity difference)
  //   wls.depth_discontinuity_radius round(radius s); wls.lrc_threshold round(threshold s)
  // and kept as they are: uniqueness_ratio, left_right_max_diff_px (1 px is the finest check at
  // any scale), the pre-filter type and caps, texture_threshold, the SGBM mode and colour, WLS
  // lambda and sigma_color.
  DisparityOptions AtMatchScale() const;
  // True when the matcher reads the BGR images themselves (SGBM with colour), not grey ones.
  bool MatchesColour() const { return method == DisparityMethod::kSemiGlobal && sgbm.colour; }
};

// Runs OpenCV's matcher. Not thread-safe (OpenCV's matcher keeps buffers); use one per thread. The
// matcher itself is parallel over rows with OpenCV's parallel_for_.
class DisparityMatcher {
 public:
  explicit DisparityMatcher(const DisparityOptions& options = {});
  const DisparityOptions& options() const { return options_; }
  // The settings OpenCV's matcher runs with: options().AtMatchScale().
  const DisparityOptions& matching_options() const { return matching_; }

  // Requires: rectified 8-bit images of equal size, grey (CV_8UC1) or BGR (CV_8UC3, converted to
  // grey unless options().MatchesColour()). Returns CV_32FC1 disparity in pixels of the left image,
  // kInvalidDisparity where there is none. With match_scale < 1 the pair is matched at MatchSize()
  // and the result brought back to the images' size by UpsampleDisparity.
  cv::Mat Compute(const cv::Mat& left, const cv::Mat& right);

  // The same, but returns OpenCV's raw CV_16SC1 output: disparity * 16, values <= 0 invalid (this
  // is what the fused encoders read). Requires grey images, or BGR ones when MatchesColour(), as
  // the matcher takes them: already resized to MatchSize() when match_scale < 1 (the output is in
  // their pixels; ResizeForMatching). With the WLS filter, `guide` (8-bit grey or BGR of the left's
  // size; empty: the left image) guides it.
  cv::Mat ComputeFixedPoint(const cv::Mat& left, const cv::Mat& right,
                            const cv::Mat& guide = cv::Mat());

 private:
  DisparityOptions options_;
  DisparityOptions matching_;             // options_.AtMatchScale()
  cv::Ptr<cv::Algorithm> matcher_;        // cv::StereoBM or cv::StereoSGBM
  cv::Ptr<cv::Algorithm> right_matcher_;  // with WLS: ximgproc's right matcher
  cv::Ptr<cv::Algorithm> wls_filter_;     // with WLS: ximgproc::DisparityWLSFilter
};

// Throws std::runtime_error naming `image` when an image of `size` is too small for the matcher of
// `options` (at its match scale: MatchSize(size) and AtMatchScale()): its block must be smaller
// than the image's shorter side, and min_disparity + num_disparities less than its width (else
// OpenCV fails, or marks every pixel invalid). The matcher checks the same, but knows no file; the
// readers of a stereo pair call this after reading.
void CheckImageFitsMatcher(const DisparityOptions& options, const cv::Size& size,
                           const std::filesystem::path& image);

// Converts OpenCV's CV_16SC1 (disparity * 16) to CV_32FC1 pixels with kInvalidDisparity for <= 0.
cv::Mat DisparityFromFixedPoint(const cv::Mat& fixed_point);

// An image resized to `match_size` for the matcher (INTER_AREA; shared when it has that size).
cv::Mat ResizeForMatching(const cv::Mat& image, cv::Size match_size);

// A CV_32FC1 disparity of a match-scale image brought to `size` (the full image's): each output
// pixel takes the value of the match-scale pixel under its centre (INTER_NEAREST_EXACT), valid
// values multiplied by size.width / disparity_px.cols (match-scale px -> image px), invalid ones
// kept invalid. Shared when already of `size`.
cv::Mat UpsampleDisparity(const cv::Mat& disparity_px, cv::Size size);

// Converts an 8-bit BGR (or already grey) image to CV_8UC1 grey. Grey input is returned shared.
cv::Mat ToGrey(const cv::Mat& image);

// --- KITTI stereo format: uint16 PNG holding round(disparity * 256), 0 = invalid. ---

// Writes atomically. Valid disparities are clamped to [1/256, 255.99] px; invalid pixels write 0.
void WriteKittiDisparity(const std::filesystem::path& path, const cv::Mat& disparity_px);
// Returns CV_32FC1 with kInvalidDisparity where the file holds 0. Throws std::runtime_error naming
// the file if it is missing, unreadable or not a 16-bit single-channel image.
cv::Mat ReadKittiDisparity(const std::filesystem::path& path);
// The same from a PNG file's bytes (the fuzz target's entry); `source` names it in errors.
cv::Mat DecodeKittiDisparity(std::string_view bytes, const std::string& source);

// --- Accuracy against ground truth. ---

struct DisparityErrorOptions {
  double bad_threshold_px = 2.0;  // "bad pixel": |estimate - truth| > this (Middlebury's bad-2.0)
  // KITTI's D1 outlier: error > d1_abs_px AND error > d1_relative * truth.
  double d1_abs_px = 3.0;
  double d1_relative = 0.05;
  void Check() const;
};

// Two D1 figures: KITTI's D1-all is over every pixel with ground truth, so a pixel the matcher left
// without a disparity counts as an outlier (KITTI's devkit first fills such pixels by background
// interpolation and scores the filled value; stereodet does not interpolate, so its D1-all is the
// devkit's figure for an estimate whose holes are all wrong: an upper bound, equal when the map is
// dense). d1_rate is over the estimated pixels only, the figure BM's sparse maps are usually quoted
// with; read it beside the density.
struct DisparityErrorStats {
  long ground_truth_pixels = 0;  // pixels with a valid ground truth
  long estimated_pixels = 0;     // ... of which the estimate is valid too
  long bad_pixels = 0;           // ... of which |error| > bad_threshold
  long d1_outlier_pixels = 0;    // ... of which the error is a D1 outlier
  double density = 0;            // estimated_pixels / ground_truth_pixels
  double bad_rate = 0;  // fraction of estimated_pixels that are bad (error > bad_threshold)
  double d1_rate = 0;   // fraction of estimated_pixels that are D1 outliers (estimated only)
  // KITTI's D1-all: (D1 outliers + pixels with ground truth but no estimate) / ground_truth_pixels.
  double d1_all_rate = 0;
  double mean_abs_error_px = 0;  // over estimated_pixels
};

// Pools per-frame stats: sums the counts and recomputes every rate from them (mean error weighted
// by each frame's estimated pixels). Rates are 0 where their denominator is.
DisparityErrorStats PoolDisparityErrors(const std::vector<DisparityErrorStats>& frames);

// Compares an estimate with ground truth (both CV_32FC1, same size; invalid = !IsValidDisparity).
// Rates but d1_all_rate are over pixels where both are valid; d1_all_rate over ground-truth pixels
// (0 when there are none).
DisparityErrorStats EvaluateDisparity(const cv::Mat& estimate_px, const cv::Mat& truth_px,
                                      const DisparityErrorOptions& options = {});

}  // namespace stereodet

#endif  // STEREODET_STEREO_DISPARITY_H_
