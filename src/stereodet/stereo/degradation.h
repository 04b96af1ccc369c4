// Image degradation for robustness studies: a Gaussian blur modelling defocus (the paper blurs the
// network's input image at evaluation time, not at training time).
#ifndef STEREODET_STEREO_DEGRADATION_H_
#define STEREODET_STEREO_DEGRADATION_H_

#include <opencv2/core.hpp>
#include <optional>
#include <string_view>

namespace stereodet {

enum class BlurMode {
  kNetworkImage,  // blur only the image the network sees; stereo uses the sharp pair (the paper)
  kBothBeforeMatching,  // blur both images before matching: degraded stereo too (correlated
                        // defocus)
};
const char* BlurModeName(BlurMode mode);  // "image", "both"
std::optional<BlurMode> ParseBlurMode(std::string_view text);

// The largest blur sigma accepted (pixels): a 601-px kernel, far past any defocus study (the
// paper's largest is 5 px); beyond it a blur only burns time.
inline constexpr double kMaxBlurSigmaPx = 100;

struct BlurOptions {
  double sigma_px = 0.0;  // in [0, kMaxBlurSigmaPx], Gaussian standard deviation; 0 = no blur
  BlurMode mode = BlurMode::kNetworkImage;
  void Check() const;
};

// The kernel side used for `sigma_px`: 2 * ceil(3 sigma) + 1 (covers +-3 sigma, > 99.7% of the
// mass), and 1 for sigma 0.
int GaussianKernelSize(double sigma_px);

// Blurs with a separable Gaussian of `sigma_px` (border: reflect-101). Sigma 0 returns an identical
// copy. Throws std::invalid_argument for a sigma outside [0, kMaxBlurSigmaPx] (NaN included).
cv::Mat GaussianBlurImage(const cv::Mat& image, double sigma_px);

}  // namespace stereodet

#endif  // STEREODET_STEREO_DEGRADATION_H_
