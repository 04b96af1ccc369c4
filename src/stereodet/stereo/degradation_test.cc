#include "stereodet/stereo/degradation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <opencv2/core.hpp>

namespace stereodet {
namespace {

cv::Mat Noise() {
  cv::Mat image(60, 80, CV_8UC3);
  cv::RNG rng(9);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(BlurTest, SigmaZeroIsTheIdentity) {
  const cv::Mat image = Noise();
  const cv::Mat out = GaussianBlurImage(image, 0.0);
  EXPECT_EQ(cv::norm(image, out, cv::NORM_INF), 0.0);
  EXPECT_NE(out.data, image.data);  // a copy: callers may modify it
}

TEST(BlurTest, KernelSizeFromSigma) {
  EXPECT_EQ(GaussianKernelSize(0.0), 1);
  EXPECT_EQ(GaussianKernelSize(0.5), 5);  // 2 * ceil(1.5) + 1
  EXPECT_EQ(GaussianKernelSize(1.0), 7);
  EXPECT_EQ(GaussianKernelSize(2.2), 15);  // 2 * ceil(6.6) + 1
  EXPECT_THROW(GaussianKernelSize(-1.0), std::invalid_argument);
}

TEST(BlurTest, BlurSmoothsNoiseAndKeepsConstants) {
  const cv::Mat image = Noise();
  cv::Scalar mean_in, std_in, mean_out, std_out;
  cv::meanStdDev(image, mean_in, std_in);
  cv::meanStdDev(GaussianBlurImage(image, 2.0), mean_out, std_out);
  EXPECT_LT(std_out[0], 0.3 * std_in[0]);
  EXPECT_NEAR(mean_out[0], mean_in[0], 2.0);
  const cv::Mat flat(30, 30, CV_8UC1, cv::Scalar(77));
  EXPECT_EQ(cv::norm(GaussianBlurImage(flat, 3.0), flat, cv::NORM_INF), 0.0);
  EXPECT_THROW(GaussianBlurImage(flat, std::nan("")), std::invalid_argument);
}

TEST(BlurTest, ModeNames) {
  EXPECT_EQ(ParseBlurMode("image"), BlurMode::kNetworkImage);
  EXPECT_EQ(ParseBlurMode("both"), BlurMode::kBothBeforeMatching);
  EXPECT_STREQ(BlurModeName(BlurMode::kBothBeforeMatching), "both");
  for (BlurMode mode : {BlurMode::kNetworkImage, BlurMode::kBothBeforeMatching}) {
    EXPECT_EQ(ParseBlurMode(BlurModeName(mode)), mode);
  }
  EXPECT_EQ(ParseBlurMode("left"), std::nullopt);
  BlurOptions options;
  options.sigma_px = -0.5;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(BlurTest, SigmaIsBoundedSoNoRunTakesMinutes) {
  // The audit's 1e300 applied no blur (a kernel size overflowed int) and 1e6 ran for minutes.
  BlurOptions options;
  options.sigma_px = kMaxBlurSigmaPx;
  EXPECT_NO_THROW(options.Check());
  EXPECT_EQ(GaussianKernelSize(kMaxBlurSigmaPx), 601);
  for (double sigma : {100.5, 1e6, 1e300, std::numeric_limits<double>::infinity()}) {
    options.sigma_px = sigma;
    EXPECT_THROW(options.Check(), std::invalid_argument) << sigma;
    EXPECT_THROW(GaussianKernelSize(sigma), std::invalid_argument) << sigma;
  }
}

}  // namespace
}  // namespace stereodet
