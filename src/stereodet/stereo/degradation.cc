#include "stereodet/stereo/degradation.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stereodet/util/check.h"

namespace stereodet {

const char* BlurModeName(BlurMode mode) {
  return mode == BlurMode::kNetworkImage ? "image" : "both";
}

std::optional<BlurMode> ParseBlurMode(std::string_view text) {
  for (BlurMode mode : {BlurMode::kNetworkImage, BlurMode::kBothBeforeMatching}) {
    if (text == BlurModeName(mode)) return mode;
  }
  return std::nullopt;
}

void BlurOptions::Check() const {
  STEREODET_CHECK(sigma_px >= 0 && sigma_px <= kMaxBlurSigmaPx)
      << "blur sigma must be in [0, " << kMaxBlurSigmaPx << "] px, got " << sigma_px;
}

int GaussianKernelSize(double sigma_px) {
  STEREODET_CHECK(sigma_px >= 0 && sigma_px <= kMaxBlurSigmaPx)
      << "blur sigma must be in [0, " << kMaxBlurSigmaPx << "] px, got " << sigma_px;
  if (sigma_px == 0) return 1;
  return 2 * static_cast<int>(std::ceil(3.0 * sigma_px)) + 1;
}

cv::Mat GaussianBlurImage(const cv::Mat& image, double sigma_px) {
  const int size = GaussianKernelSize(sigma_px);
  if (size == 1) return image.clone();
  cv::Mat blurred;
  cv::GaussianBlur(image, blurred, cv::Size(size, size), sigma_px, sigma_px,
                   cv::BORDER_REFLECT_101);
  return blurred;
}

}  // namespace stereodet
