#include "stereodet/stereo/disparity.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/disparity_filter.hpp>
#include <sstream>

#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

const char* DisparityMethodName(DisparityMethod method) {
  return method == DisparityMethod::kBlockMatching ? "bm" : "sgbm";
}

std::optional<DisparityMethod> ParseDisparityMethod(std::string_view text) {
  for (DisparityMethod method : {DisparityMethod::kBlockMatching, DisparityMethod::kSemiGlobal}) {
    if (text == DisparityMethodName(method)) return method;
  }
  return std::nullopt;
}

const char* SgbmModeName(SgbmMode mode) {
  switch (mode) {
    case SgbmMode::kSgbm:
      return "sgbm";
    case SgbmMode::kHh:
      return "hh";
    case SgbmMode::kSgbm3Way:
      return "sgbm3way";
    case SgbmMode::kHh4:
      return "hh4";
  }
  return "sgbm";
}

std::optional<SgbmMode> ParseSgbmMode(std::string_view text) {
  for (SgbmMode mode : {SgbmMode::kSgbm, SgbmMode::kHh, SgbmMode::kSgbm3Way, SgbmMode::kHh4}) {
    if (text == SgbmModeName(mode)) return mode;
  }
  return std::nullopt;
}

namespace {

int OpenCvSgbmMode(SgbmMode mode) {
  switch (mode) {
    case SgbmMode::kSgbm:
      return cv::StereoSGBM::MODE_SGBM;
    case SgbmMode::kHh:
      return cv::StereoSGBM::MODE_HH;
    case SgbmMode::kSgbm3Way:
      return cv::StereoSGBM::MODE_SGBM_3WAY;
    case SgbmMode::kHh4:
      return cv::StereoSGBM::MODE_HH4;
  }
  return cv::StereoSGBM::MODE_SGBM;
}

}  // namespace

void BlockMatchingOptions::Check() const {
  STEREODET_CHECK(block_size >= 5 && block_size <= 255 && block_size % 2 == 1)
      << "BM block_size must be odd and in 5..255, got " << block_size;
  STEREODET_CHECK(prefilter_size >= 5 && prefilter_size <= 255 && prefilter_size % 2 == 1)
      << "BM prefilter_size must be odd and in 5..255, got " << prefilter_size;
  STEREODET_CHECK(prefilter_cap >= 1 && prefilter_cap <= 63)
      << "BM prefilter_cap must be in 1..63, got " << prefilter_cap;
  STEREODET_CHECK(texture_threshold >= 0)
      << "BM texture_threshold must be >= 0, got " << texture_threshold;
}

void SemiGlobalOptions::Check() const {
  STEREODET_CHECK(block_size >= 1 && block_size <= 255 && block_size % 2 == 1)
      << "SGBM block_size must be odd and in 1..255, got " << block_size;
  // In 64-bit first: a large per-pixel penalty times 3 x 255^2 would overflow an int.
  STEREODET_CHECK(p1_per_pixel > 0 && p1_per_pixel <= 10000 && p2_per_pixel > 0 &&
                  p2_per_pixel <= 10000)
      << "SGBM p1_per_pixel and p2_per_pixel must be in 1..10000, got " << p1_per_pixel << ", "
      << p2_per_pixel;
  STEREODET_CHECK(!p1 || (*p1 > 0 && *p1 < 1000000000))
      << "SGBM P1 must be in 1..999999999, got " << *p1;
  STEREODET_CHECK(!p2 || (*p2 > 0 && *p2 < 1000000000))
      << "SGBM P2 must be in 1..999999999, got " << *p2;
  const int64_t area = static_cast<int64_t>(Channels()) * block_size * block_size;
  const int64_t p1_value = p1 ? *p1 : p1_per_pixel * area;
  const int64_t p2_value = p2 ? *p2 : p2_per_pixel * area;
  STEREODET_CHECK(p1_value < p2_value)
      << "SGBM penalties must satisfy 0 < P1 < P2, got P1 " << p1_value << ", P2 " << p2_value;
  STEREODET_CHECK(prefilter_cap >= 1 && prefilter_cap <= 1023)
      << "SGBM prefilter_cap must be in 1..1023, got " << prefilter_cap;
}

void WlsFilterOptions::Check() const {
  STEREODET_CHECK(std::isfinite(lambda) && lambda > 0 && lambda <= 1e9)
      << "WLS lambda must be in (0, 1e9], got " << lambda;
  STEREODET_CHECK(std::isfinite(sigma_color) && sigma_color > 0 && sigma_color <= 1000)
      << "WLS sigma_color must be in (0, 1000], got " << sigma_color;
  STEREODET_CHECK(lrc_threshold >= 0 && lrc_threshold <= 16 * 1024)
      << "WLS lrc_threshold must be in 0..16384 (1/16 px), got " << lrc_threshold;
  STEREODET_CHECK(depth_discontinuity_radius >= 0 && depth_discontinuity_radius <= 255)
      << "WLS depth_discontinuity_radius must be in 0..255 px, got " << depth_discontinuity_radius;
}

void DisparityOptions::Check() const {
  // 2048 px: above any rectified width stereodet reads (KITTI's is 1242), below int16 x 16.
  STEREODET_CHECK(num_disparities > 0 && num_disparities <= 2048 && num_disparities % 16 == 0)
      << "num_disparities must be a positive multiple of 16 up to 2048, got " << num_disparities;
  STEREODET_CHECK(min_disparity >= 0 && min_disparity <= 2048)
      << "min_disparity must be in 0..2048 (negative disparities have no depth), got "
      << min_disparity;
  STEREODET_CHECK(left_right_max_diff_px >= -1 && left_right_max_diff_px <= 2048)
      << "left_right_max_diff_px (disp12MaxDiff) must be in -1..2048 (-1 = off), got "
      << left_right_max_diff_px;
  STEREODET_CHECK(uniqueness_ratio >= 0 && uniqueness_ratio <= 100)
      << "uniqueness_ratio must be in 0..100, got " << uniqueness_ratio;
  STEREODET_CHECK(speckle_window_px >= 0)
      << "speckle_window_px must be >= 0, got " << speckle_window_px;
  STEREODET_CHECK(speckle_range_px >= 0 && speckle_range_px <= 2048)
      << "speckle_range_px must be in 0..2048, got " << speckle_range_px;
  if (wls.enabled) wls.Check();
  if (method == DisparityMethod::kBlockMatching) {
    bm.Check();
  } else {
    sgbm.Check();
  }
  STEREODET_CHECK(std::isfinite(match_scale) && match_scale >= 0.1 && match_scale <= 1.0)
      << "match_scale must be in [0.1, 1] (1 = full resolution), got " << match_scale;
  if (match_scale < 1.0) AtMatchScale().Check();
}

cv::Size DisparityOptions::MatchSize(cv::Size image) const {
  if (match_scale >= 1.0) return image;
  return {std::max(1, static_cast<int>(std::lround(image.width * match_scale))),
          std::max(1, static_cast<int>(std::lround(image.height * match_scale)))};
}

namespace {

// The odd integer in [x - 1, x + 1), at least `minimum`.
int OddAtLeast(double x, int minimum) {
  return std::max(minimum, 2 * static_cast<int>(std::floor(x / 2.0)) + 1);
}

}  // namespace

DisparityOptions DisparityOptions::AtMatchScale() const {
  DisparityOptions o = *this;
  o.match_scale = 1.0;
  if (match_scale >= 1.0) return o;
  const double s = match_scale;
  o.num_disparities = std::max(16, 16 * static_cast<int>(std::ceil(num_disparities * s / 16.0)));
  o.min_disparity = static_cast<int>(std::floor(min_disparity * s));
  o.bm.block_size = OddAtLeast(bm.block_size * s, 5);
  o.bm.prefilter_size = OddAtLeast(bm.prefilter_size * s, 5);
  o.sgbm.block_size = OddAtLeast(sgbm.block_size * s, 1);
  o.speckle_window_px = static_cast<int>(std::lround(speckle_window_px * s * s));
  o.speckle_range_px =
      speckle_range_px > 0 ? std::max(1, static_cast<int>(std::lround(speckle_range_px * s))) : 0;
  o.wls.depth_discontinuity_radius =
      static_cast<int>(std::lround(wls.depth_discontinuity_radius * s));
  o.wls.lrc_threshold = static_cast<int>(std::lround(wls.lrc_threshold * s));
  return o;
}

DisparityMatcher::DisparityMatcher(const DisparityOptions& options) : options_(options) {
  options_.Check();
  matching_ = options_.AtMatchScale();
  const DisparityOptions& o = matching_;
  if (o.method == DisparityMethod::kBlockMatching) {
    cv::Ptr<cv::StereoBM> bm = cv::StereoBM::create(o.num_disparities, o.bm.block_size);
    bm->setMinDisparity(o.min_disparity);
    bm->setPreFilterType(o.bm.xsobel_prefilter ? cv::StereoBM::PREFILTER_XSOBEL
                                               : cv::StereoBM::PREFILTER_NORMALIZED_RESPONSE);
    bm->setPreFilterSize(o.bm.prefilter_size);
    bm->setPreFilterCap(o.bm.prefilter_cap);
    bm->setTextureThreshold(o.bm.texture_threshold);
    bm->setUniquenessRatio(o.uniqueness_ratio);
    bm->setSpeckleWindowSize(o.speckle_window_px);
    // StereoBM filters speckles on its fixed-point output, so its range is in 1/16 px.
    bm->setSpeckleRange(o.speckle_range_px * 16);
    bm->setDisp12MaxDiff(o.left_right_max_diff_px);
    matcher_ = bm;
  } else {
    // SGBM multiplies its speckle range by 16 itself, so it takes whole pixels.
    matcher_ = cv::StereoSGBM::create(o.min_disparity, o.num_disparities, o.sgbm.block_size,
                                      o.sgbm.P1(), o.sgbm.P2(), o.left_right_max_diff_px,
                                      o.sgbm.prefilter_cap, o.uniqueness_ratio, o.speckle_window_px,
                                      o.speckle_range_px, OpenCvSgbmMode(o.sgbm.mode));
  }
  if (o.wls.enabled) {
    const cv::Ptr<cv::StereoMatcher> left = matcher_.dynamicCast<cv::StereoMatcher>();
    right_matcher_ = cv::ximgproc::createRightMatcher(left);
    cv::Ptr<cv::ximgproc::DisparityWLSFilter> filter = cv::ximgproc::createDisparityWLSFilter(left);
    filter->setLambda(o.wls.lambda);
    filter->setSigmaColor(o.wls.sigma_color);
    filter->setLRCthresh(o.wls.lrc_threshold);
    filter->setDepthDiscontinuityRadius(o.wls.depth_discontinuity_radius);
    wls_filter_ = filter;
  }
}

cv::Mat ToGrey(const cv::Mat& image) {
  STEREODET_CHECK(image.depth() == CV_8U && (image.channels() == 1 || image.channels() == 3))
      << "expected an 8-bit grey or BGR image, got type " << image.type();
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

cv::Mat DisparityMatcher::ComputeFixedPoint(const cv::Mat& left_grey, const cv::Mat& right_grey,
                                            const cv::Mat& guide) {
  const int expected = matching_.MatchesColour() ? CV_8UC3 : CV_8UC1;
  STEREODET_CHECK(left_grey.type() == expected && right_grey.type() == expected)
      << "disparity needs 8-bit " << (matching_.MatchesColour() ? "BGR" : "grey")
      << " images, got types " << left_grey.type() << " and " << right_grey.type();
  STEREODET_CHECK(left_grey.size() == right_grey.size())
      << "left and right images differ in size: " << left_grey.cols << "x" << left_grey.rows
      << " vs " << right_grey.cols << "x" << right_grey.rows;
  const int min_side = std::min(left_grey.cols, left_grey.rows);
  const int block = matching_.method == DisparityMethod::kBlockMatching ? matching_.bm.block_size
                                                                        : matching_.sgbm.block_size;
  STEREODET_CHECK(block < min_side) << "block size " << block << " does not fit the "
                                    << left_grey.cols << "x" << left_grey.rows << " image";
  // A search range as wide as the image leaves no column to match: OpenCV then marks every pixel
  // invalid, and an empty point cloud would pass for a result.
  STEREODET_CHECK(matching_.min_disparity + matching_.num_disparities < left_grey.cols)
      << "min_disparity + num_disparities (" << matching_.min_disparity << " + "
      << matching_.num_disparities << ") must be less than the image width " << left_grey.cols
      << " px";
  cv::Mat fixed_point;
  matcher_.dynamicCast<cv::StereoMatcher>()->compute(left_grey, right_grey, fixed_point);
  if (!wls_filter_) return fixed_point;
  const cv::Mat& view = guide.empty() ? left_grey : guide;
  STEREODET_CHECK(view.size() == left_grey.size() && view.depth() == CV_8U &&
                  (view.channels() == 1 || view.channels() == 3))
      << "the WLS filter's guide must be an 8-bit grey or BGR image of the left's size";
  cv::Mat right_disparity, filtered;
  right_matcher_.dynamicCast<cv::StereoMatcher>()->compute(right_grey, left_grey, right_disparity);
  wls_filter_.dynamicCast<cv::ximgproc::DisparityWLSFilter>()->filter(fixed_point, view, filtered,
                                                                      right_disparity);
  // The filter's output is CV_16S x16 like the matcher's; it may carry values beyond the search
  // range at borders, so clamp to it (the depth tables of the encoders are sized by it).
  const int16_t max_raw =
      static_cast<int16_t>((matching_.min_disparity + matching_.num_disparities) * 16);
  cv::min(filtered, cv::Scalar(max_raw), filtered);
  return filtered;
}

void CheckImageFitsMatcher(const DisparityOptions& full_options, const cv::Size& full_size,
                           const std::filesystem::path& image) {
  const DisparityOptions options = full_options.AtMatchScale();
  const cv::Size size = full_options.MatchSize(full_size);
  std::ostringstream at_scale;
  if (full_options.match_scale < 1.0) {
    at_scale << " (at --match-scale " << full_options.match_scale << ": " << size.width << "x"
             << size.height << " px)";
  }
  const int block = options.method == DisparityMethod::kBlockMatching ? options.bm.block_size
                                                                      : options.sgbm.block_size;
  STEREODET_CHECK_IO(block < std::min(size.width, size.height))
      << image.string() << ": the " << full_size.width << "x" << full_size.height << " px image"
      << at_scale.str() << " is smaller than the matcher's " << block << "x" << block
      << " px block (--block-size); a stereo image must be larger than its block";
  STEREODET_CHECK_IO(options.min_disparity + options.num_disparities < size.width)
      << image.string() << ": the image is " << full_size.width << " px wide" << at_scale.str()
      << ", no wider than the disparity search (min disparity " << options.min_disparity << " + "
      << options.num_disparities
      << " disparities), so no pixel could be matched; lower --num-disparities";
}

cv::Mat DisparityMatcher::Compute(const cv::Mat& left, const cv::Mat& right) {
  STEREODET_CHECK(left.size() == right.size())
      << "left and right images differ in size: " << left.cols << "x" << left.rows << " vs "
      << right.cols << "x" << right.rows;
  const cv::Size match_size = options_.MatchSize(left.size());
  const cv::Mat l = options_.MatchesColour() ? left : ToGrey(left);
  const cv::Mat r = options_.MatchesColour() ? right : ToGrey(right);
  const cv::Mat disparity = DisparityFromFixedPoint(
      ComputeFixedPoint(ResizeForMatching(l, match_size), ResizeForMatching(r, match_size)));
  return UpsampleDisparity(disparity, left.size());
}

cv::Mat ResizeForMatching(const cv::Mat& image, cv::Size match_size) {
  if (image.size() == match_size) return image;
  cv::Mat resized;
  cv::resize(image, resized, match_size, 0, 0, cv::INTER_AREA);
  return resized;
}

cv::Mat UpsampleDisparity(const cv::Mat& disparity_px, cv::Size size) {
  STEREODET_CHECK(disparity_px.type() == CV_32FC1 && !disparity_px.empty())
      << "UpsampleDisparity needs a CV_32FC1 disparity, got type " << disparity_px.type();
  if (disparity_px.size() == size) return disparity_px;
  cv::Mat upsampled;
  cv::resize(disparity_px, upsampled, size, 0, 0, cv::INTER_NEAREST_EXACT);
  const float factor = static_cast<float>(size.width) / static_cast<float>(disparity_px.cols);
  for (int v = 0; v < upsampled.rows; ++v) {
    float* d = upsampled.ptr<float>(v);
    for (int u = 0; u < upsampled.cols; ++u) {
      if (IsValidDisparity(d[u])) d[u] *= factor;
    }
  }
  return upsampled;
}

cv::Mat DisparityFromFixedPoint(const cv::Mat& fixed_point) {
  STEREODET_CHECK(fixed_point.type() == CV_16SC1)
      << "expected OpenCV's CV_16SC1 disparity, got type " << fixed_point.type();
  cv::Mat disparity(fixed_point.size(), CV_32FC1);
  cv::parallel_for_(cv::Range(0, fixed_point.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const int16_t* in = fixed_point.ptr<int16_t>(v);
      float* out = disparity.ptr<float>(v);
      for (int u = 0; u < fixed_point.cols; ++u) {
        out[u] = in[u] > 0 ? static_cast<float>(in[u]) * (1.0f / 16.0f) : kInvalidDisparity;
      }
    }
  });
  return disparity;
}

void WriteKittiDisparity(const std::filesystem::path& path, const cv::Mat& disparity_px) {
  STEREODET_CHECK(disparity_px.type() == CV_32FC1)
      << "disparity must be CV_32FC1, got type " << disparity_px.type();
  cv::Mat encoded(disparity_px.size(), CV_16UC1);
  for (int v = 0; v < disparity_px.rows; ++v) {
    const float* in = disparity_px.ptr<float>(v);
    uint16_t* out = encoded.ptr<uint16_t>(v);
    for (int u = 0; u < disparity_px.cols; ++u) {
      // A valid disparity never encodes as 0 (which would read back as invalid).
      out[u] = IsValidDisparity(in[u])
                   ? static_cast<uint16_t>(std::clamp(std::lround(in[u] * 256.0f), 1L, 65535L))
                   : 0;
    }
  }
  AtomicPath out(path);
  STEREODET_CHECK_IO(cv::imwrite(out.temp_path().string(), encoded))
      << "cannot write disparity image " << path;
  out.Commit();
}

namespace {

// The CV_32FC1 disparity of KITTI's encoding (uint16, round(d * 256), 0 = invalid).
cv::Mat FromKittiEncoding(const cv::Mat& encoded, const std::string& source) {
  STEREODET_CHECK_IO(encoded.type() == CV_16UC1)
      << source << ": a KITTI disparity image must be a 16-bit grey PNG, got OpenCV type "
      << encoded.type();
  cv::Mat disparity(encoded.size(), CV_32FC1);
  for (int v = 0; v < encoded.rows; ++v) {
    const uint16_t* in = encoded.ptr<uint16_t>(v);
    float* out = disparity.ptr<float>(v);
    for (int u = 0; u < encoded.cols; ++u) {
      out[u] = in[u] == 0 ? kInvalidDisparity : static_cast<float>(in[u]) / 256.0f;
    }
  }
  return disparity;
}

}  // namespace

cv::Mat ReadKittiDisparity(const std::filesystem::path& path) {
  return FromKittiEncoding(ReadImage(path, cv::IMREAD_UNCHANGED, "disparity image"), path.string());
}

cv::Mat DecodeKittiDisparity(std::string_view bytes, const std::string& source) {
  cv::Mat encoded;
  try {
    const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8UC1,
                         const_cast<char*>(bytes.data()));
    if (!bytes.empty()) encoded = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    STEREODET_THROW_IO() << "cannot read disparity image " << source << ": " << e.err;
  }
  STEREODET_CHECK_IO(!encoded.empty()) << "cannot read disparity image " << source;
  return FromKittiEncoding(encoded, source);
}

void DisparityErrorOptions::Check() const {
  STEREODET_CHECK(bad_threshold_px >= 0 && d1_abs_px >= 0 && d1_relative >= 0)
      << "disparity error thresholds must be >= 0";
}

namespace {

// The rates from the counts; mean_abs_error_px holds the sum of the errors on entry.
void FinishRates(DisparityErrorStats& stats) {
  if (stats.ground_truth_pixels > 0) {
    const double truth = static_cast<double>(stats.ground_truth_pixels);
    stats.density = stats.estimated_pixels / truth;
    stats.d1_all_rate =
        (stats.d1_outlier_pixels + (stats.ground_truth_pixels - stats.estimated_pixels)) / truth;
  }
  if (stats.estimated_pixels > 0) {
    const double estimated = static_cast<double>(stats.estimated_pixels);
    stats.bad_rate = stats.bad_pixels / estimated;
    stats.d1_rate = stats.d1_outlier_pixels / estimated;
    stats.mean_abs_error_px /= estimated;
  } else {
    stats.mean_abs_error_px = 0;
  }
}

}  // namespace

DisparityErrorStats EvaluateDisparity(const cv::Mat& estimate_px, const cv::Mat& truth_px,
                                      const DisparityErrorOptions& options) {
  options.Check();
  STEREODET_CHECK(estimate_px.type() == CV_32FC1 && truth_px.type() == CV_32FC1)
      << "EvaluateDisparity needs CV_32FC1 images";
  STEREODET_CHECK(estimate_px.size() == truth_px.size())
      << "estimate and ground truth differ in size";
  DisparityErrorStats stats;
  long bad = 0, d1 = 0;
  double abs_sum = 0;
  for (int v = 0; v < truth_px.rows; ++v) {
    const float* truth = truth_px.ptr<float>(v);
    const float* estimate = estimate_px.ptr<float>(v);
    for (int u = 0; u < truth_px.cols; ++u) {
      if (!IsValidDisparity(truth[u])) continue;
      ++stats.ground_truth_pixels;
      if (!IsValidDisparity(estimate[u])) continue;
      ++stats.estimated_pixels;
      const double error = std::abs(static_cast<double>(estimate[u]) - truth[u]);
      abs_sum += error;
      if (error > options.bad_threshold_px) ++bad;
      if (error > options.d1_abs_px && error > options.d1_relative * truth[u]) ++d1;
    }
  }
  stats.bad_pixels = bad;
  stats.d1_outlier_pixels = d1;
  stats.mean_abs_error_px = abs_sum;  // a sum until FinishRates divides it
  FinishRates(stats);
  return stats;
}

DisparityErrorStats PoolDisparityErrors(const std::vector<DisparityErrorStats>& frames) {
  DisparityErrorStats pooled;
  for (const DisparityErrorStats& frame : frames) {
    pooled.ground_truth_pixels += frame.ground_truth_pixels;
    pooled.estimated_pixels += frame.estimated_pixels;
    pooled.bad_pixels += frame.bad_pixels;
    pooled.d1_outlier_pixels += frame.d1_outlier_pixels;
    pooled.mean_abs_error_px += frame.mean_abs_error_px * frame.estimated_pixels;
  }
  FinishRates(pooled);
  return pooled;
}

}  // namespace stereodet
