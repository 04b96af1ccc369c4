#include "stereodet/stereo/disparity.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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
  STEREODET_CHECK(block_size >= 1 && block_size % 2 == 1)
      << "SGBM block_size must be odd and >= 1, got " << block_size;
  STEREODET_CHECK(p1_per_pixel > 0 && p2_per_pixel > p1_per_pixel)
      << "SGBM penalties must satisfy 0 < p1 < p2, got p1 " << p1_per_pixel << ", p2 "
      << p2_per_pixel;
  STEREODET_CHECK(prefilter_cap >= 1) << "SGBM prefilter_cap must be >= 1, got " << prefilter_cap;
}

void DisparityOptions::Check() const {
  STEREODET_CHECK(num_disparities > 0 && num_disparities % 16 == 0)
      << "num_disparities must be a positive multiple of 16, got " << num_disparities;
  STEREODET_CHECK(min_disparity >= 0)
      << "min_disparity must be >= 0 (negative disparities have no depth), got " << min_disparity;
  STEREODET_CHECK(uniqueness_ratio >= 0 && uniqueness_ratio <= 100)
      << "uniqueness_ratio must be in 0..100, got " << uniqueness_ratio;
  STEREODET_CHECK(speckle_window_px >= 0)
      << "speckle_window_px must be >= 0, got " << speckle_window_px;
  STEREODET_CHECK(speckle_range_px >= 0)
      << "speckle_range_px must be >= 0, got " << speckle_range_px;
  if (method == DisparityMethod::kBlockMatching) {
    bm.Check();
  } else {
    sgbm.Check();
  }
}

DisparityMatcher::DisparityMatcher(const DisparityOptions& options) : options_(options) {
  options_.Check();
  const DisparityOptions& o = options_;
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
    const int area = o.sgbm.block_size * o.sgbm.block_size;
    // SGBM multiplies its speckle range by 16 itself, so it takes whole pixels.
    matcher_ = cv::StereoSGBM::create(
        o.min_disparity, o.num_disparities, o.sgbm.block_size, o.sgbm.p1_per_pixel * area,
        o.sgbm.p2_per_pixel * area, o.left_right_max_diff_px, o.sgbm.prefilter_cap,
        o.uniqueness_ratio, o.speckle_window_px, o.speckle_range_px,
        o.sgbm.full_8_directions ? cv::StereoSGBM::MODE_HH : cv::StereoSGBM::MODE_SGBM);
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

cv::Mat DisparityMatcher::ComputeFixedPoint(const cv::Mat& left_grey, const cv::Mat& right_grey) {
  STEREODET_CHECK(left_grey.type() == CV_8UC1 && right_grey.type() == CV_8UC1)
      << "disparity needs 8-bit grey images, got types " << left_grey.type() << " and "
      << right_grey.type();
  STEREODET_CHECK(left_grey.size() == right_grey.size())
      << "left and right images differ in size: " << left_grey.cols << "x" << left_grey.rows
      << " vs " << right_grey.cols << "x" << right_grey.rows;
  const int min_side = std::min(left_grey.cols, left_grey.rows);
  const int block = options_.method == DisparityMethod::kBlockMatching ? options_.bm.block_size
                                                                       : options_.sgbm.block_size;
  STEREODET_CHECK(block < min_side) << "block size " << block << " does not fit the "
                                    << left_grey.cols << "x" << left_grey.rows << " image";
  // A search range as wide as the image leaves no column to match: OpenCV then marks every pixel
  // invalid, and an empty point cloud would pass for a result.
  STEREODET_CHECK(options_.min_disparity + options_.num_disparities < left_grey.cols)
      << "min_disparity + num_disparities (" << options_.min_disparity << " + "
      << options_.num_disparities << ") must be less than the image width " << left_grey.cols
      << " px";
  cv::Mat fixed_point;
  matcher_.dynamicCast<cv::StereoMatcher>()->compute(left_grey, right_grey, fixed_point);
  return fixed_point;
}

void CheckImageFitsMatcher(const DisparityOptions& options, const cv::Size& size,
                           const std::filesystem::path& image) {
  const int block = options.method == DisparityMethod::kBlockMatching ? options.bm.block_size
                                                                      : options.sgbm.block_size;
  STEREODET_CHECK_IO(block < std::min(size.width, size.height))
      << image.string() << ": the " << size.width << "x" << size.height
      << " px image is smaller than the matcher's " << block << "x" << block
      << " px block (--block-size); a stereo image must be larger than its block";
  STEREODET_CHECK_IO(options.min_disparity + options.num_disparities < size.width)
      << image.string() << ": the image is " << size.width
      << " px wide, no wider than the disparity search (min disparity " << options.min_disparity
      << " + " << options.num_disparities
      << " disparities), so no pixel could be matched; lower --num-disparities";
}

cv::Mat DisparityMatcher::Compute(const cv::Mat& left, const cv::Mat& right) {
  return DisparityFromFixedPoint(ComputeFixedPoint(ToGrey(left), ToGrey(right)));
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
  if (stats.ground_truth_pixels > 0) {
    stats.density = static_cast<double>(stats.estimated_pixels) / stats.ground_truth_pixels;
  }
  if (stats.estimated_pixels > 0) {
    stats.bad_rate = static_cast<double>(bad) / stats.estimated_pixels;
    stats.d1_rate = static_cast<double>(d1) / stats.estimated_pixels;
    stats.mean_abs_error_px = abs_sum / stats.estimated_pixels;
  }
  return stats;
}

}  // namespace stereodet
