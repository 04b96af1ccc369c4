#include "stereodet/stereo/visualize.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stereodet/util/check.h"

namespace stereodet {
namespace {

// Maps t in [0, 1] (NaN = no data) through the turbo colour map; no-data pixels are black.
cv::Mat ColourizeUnit(const cv::Mat& unit) {
  cv::Mat grey(unit.size(), CV_8UC1);
  cv::Mat valid(unit.size(), CV_8UC1);
  for (int v = 0; v < unit.rows; ++v) {
    const float* t = unit.ptr<float>(v);
    uint8_t* g = grey.ptr<uint8_t>(v);
    uint8_t* m = valid.ptr<uint8_t>(v);
    for (int u = 0; u < unit.cols; ++u) {
      const bool ok = !std::isnan(t[u]);
      m[u] = ok ? 255 : 0;
      g[u] = ok ? static_cast<uint8_t>(std::lround(255.0 * std::clamp(t[u], 0.0f, 1.0f))) : 0;
    }
  }
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_TURBO);
  colour.setTo(cv::Scalar::all(0), ~valid);
  return colour;
}

}  // namespace

cv::Mat ColourizeDisparity(const cv::Mat& disparity_px, double max_disparity_px) {
  STEREODET_CHECK(disparity_px.type() == CV_32FC1) << "disparity must be CV_32FC1";
  STEREODET_CHECK(max_disparity_px > 0) << "max disparity must be > 0";
  cv::Mat unit(disparity_px.size(), CV_32FC1);
  for (int v = 0; v < unit.rows; ++v) {
    const float* d = disparity_px.ptr<float>(v);
    float* t = unit.ptr<float>(v);
    for (int u = 0; u < unit.cols; ++u) {
      t[u] = d[u] > 0 ? static_cast<float>(d[u] / max_disparity_px) : NAN;
    }
  }
  return ColourizeUnit(unit);
}

cv::Mat ColourizeDepth(const cv::Mat& depth_m, double min_depth_m) {
  STEREODET_CHECK(depth_m.type() == CV_32FC1) << "depth must be CV_32FC1";
  STEREODET_CHECK(min_depth_m > 0) << "min depth must be > 0";
  cv::Mat unit(depth_m.size(), CV_32FC1);
  for (int v = 0; v < unit.rows; ++v) {
    const float* z = depth_m.ptr<float>(v);
    float* t = unit.ptr<float>(v);
    for (int u = 0; u < unit.cols; ++u) {
      t[u] = z[u] > 0 ? static_cast<float>(min_depth_m / z[u]) : NAN;
    }
  }
  return ColourizeUnit(unit);
}

cv::Mat ColourizeHeight(const cv::Mat& height_m, double min_m, double max_m) {
  STEREODET_CHECK(height_m.type() == CV_32FC1) << "height must be CV_32FC1";
  STEREODET_CHECK(min_m < max_m) << "height range is empty";
  cv::Mat unit(height_m.size(), CV_32FC1);
  for (int v = 0; v < unit.rows; ++v) {
    const float* h = height_m.ptr<float>(v);
    float* t = unit.ptr<float>(v);
    for (int u = 0; u < unit.cols; ++u) {
      t[u] = std::isnan(h[u]) ? NAN : static_cast<float>((h[u] - min_m) / (max_m - min_m));
    }
  }
  return ColourizeUnit(unit);
}

void BirdsEyeOptions::Check() const {
  STEREODET_CHECK(forward_m > 0 && side_m > 0 && resolution_m > 0 && min_z_m < max_z_m)
      << "bird's-eye view ranges must be positive";
  STEREODET_CHECK(forward_m / resolution_m <= 8192 && 2 * side_m / resolution_m <= 8192)
      << "bird's-eye view would exceed 8192 pixels a side";
}

cv::Mat RenderBirdsEye(const std::vector<VeloPoint>& points, const BirdsEyeOptions& options) {
  options.Check();
  const int rows = static_cast<int>(std::ceil(options.forward_m / options.resolution_m));
  const int cols = static_cast<int>(std::ceil(2 * options.side_m / options.resolution_m));
  cv::Mat image(rows, cols, CV_8UC3, cv::Scalar::all(0));
  for (int ring_m = 10; ring_m <= options.forward_m; ring_m += 10) {
    cv::circle(image, cv::Point(cols / 2, rows), static_cast<int>(ring_m / options.resolution_m),
               cv::Scalar::all(60), 1, cv::LINE_AA);
  }
  cv::Mat level(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) level.at<uint8_t>(i) = static_cast<uint8_t>(i);
  cv::Mat palette;
  cv::applyColorMap(level, palette, cv::COLORMAP_TURBO);
  for (const VeloPoint& p : points) {
    const int row = rows - 1 - static_cast<int>(std::floor(p.x / options.resolution_m));
    const int col = cols / 2 - static_cast<int>(std::floor(p.y / options.resolution_m));
    if (row < 0 || row >= rows || col < 0 || col >= cols) continue;
    const double t =
        std::clamp((p.z - options.min_z_m) / (options.max_z_m - options.min_z_m), 0.0, 1.0);
    image.at<cv::Vec3b>(row, col) = palette.at<cv::Vec3b>(static_cast<int>(std::lround(255 * t)));
  }
  return image;
}

cv::Vec3b TurboColour(double t) {
  cv::Mat level(1, 1, CV_8UC1,
                cv::Scalar(static_cast<int>(std::lround(255 * std::clamp(t, 0.0, 1.0)))));
  cv::Mat colour;
  cv::applyColorMap(level, colour, cv::COLORMAP_TURBO);
  return colour.at<cv::Vec3b>(0, 0);
}

// The band's layout: caption baseline at 16 px, the bar 12 px tall from 24 px, tick texts below.
int ColourBarBandHeight() { return 56; }
int ColourBarMarginPx() { return 12; }
int ColourBarTopPx(int picture_rows) { return picture_rows + 24; }
int ColourBarHeightPx() { return 12; }

cv::Mat WithColourBar(const cv::Mat& picture, const ColourBar& bar) {
  STEREODET_CHECK(!picture.empty() && picture.type() == CV_8UC3)
      << "colour bar: the picture must be 8-bit BGR and not empty";
  const int margin = ColourBarMarginPx();
  STEREODET_CHECK(picture.cols >= 4 * margin)
      << "colour bar: a picture " << picture.cols << " px wide is too narrow";
  for (const auto& [t, text] : bar.ticks) {
    STEREODET_CHECK(t >= 0 && t <= 1)
        << "colour bar: tick '" << text << "' at " << t << " is outside [0, 1]";
  }
  cv::Mat out(picture.rows + ColourBarBandHeight(), picture.cols, CV_8UC3, cv::Scalar::all(255));
  picture.copyTo(out(cv::Rect(0, 0, picture.cols, picture.rows)));
  const int left = margin, right = picture.cols - margin, top = ColourBarTopPx(picture.rows);
  const double font = picture.cols >= 600 ? 0.45 : 0.35;
  cv::putText(out, bar.caption, cv::Point(left, picture.rows + 16), cv::FONT_HERSHEY_SIMPLEX, font,
              cv::Scalar::all(20), 1, cv::LINE_AA);
  for (int x = left; x < right; ++x) {
    const cv::Vec3b c = TurboColour(static_cast<double>(x - left) / (right - 1 - left));
    cv::line(out, cv::Point(x, top), cv::Point(x, top + ColourBarHeightPx() - 1),
             cv::Scalar(c[0], c[1], c[2]));
  }
  for (const auto& [t, text] : bar.ticks) {
    const int x = left + static_cast<int>(std::lround(t * (right - 1 - left)));
    const int bottom = top + ColourBarHeightPx();
    cv::line(out, cv::Point(x, bottom), cv::Point(x, bottom + 3), cv::Scalar::all(20));
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, font, 1, &baseline);
    const int text_x = std::clamp(x - size.width / 2, 0, std::max(0, picture.cols - size.width));
    cv::putText(out, text, cv::Point(text_x, bottom + 5 + size.height), cv::FONT_HERSHEY_SIMPLEX,
                font, cv::Scalar::all(20), 1, cv::LINE_AA);
  }
  return out;
}

}  // namespace stereodet
