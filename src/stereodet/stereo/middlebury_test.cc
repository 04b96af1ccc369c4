// Accuracy on data no one here made: the Middlebury 2006 "Aloe" pair with its ground truth, shipped
// by Debian's opencv-doc (scripts/install-deps.sh installs it).
//
// The full-size images are 1282 x 1110 with disparities 43..211 px. We halve them (INTER_AREA for
// the images; nearest neighbour for the ground truth, whose values are halved too) so that the test
// is fast and the range fits 112 disparities. The figures held here are those measured and
// documented in docs/stereo.md, with a small margin.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "stereodet/stereo/disparity.h"

namespace stereodet {
namespace {

const std::filesystem::path kAloeDir = "/usr/share/doc/opencv-doc/examples/data";

struct HalfAloe {
  cv::Mat left, right, truth_px;
};

HalfAloe LoadHalfAloe() {
  const cv::Mat left = cv::imread((kAloeDir / "aloeL.jpg").string(), cv::IMREAD_COLOR);
  const cv::Mat right = cv::imread((kAloeDir / "aloeR.jpg").string(), cv::IMREAD_COLOR);
  const cv::Mat truth = cv::imread((kAloeDir / "aloeGT.png").string(), cv::IMREAD_GRAYSCALE);
  HalfAloe aloe;
  if (left.empty() || right.empty() || truth.empty()) return aloe;
  cv::resize(left, aloe.left, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::resize(right, aloe.right, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  cv::Mat truth_half;
  cv::resize(truth, truth_half, aloe.left.size(), 0, 0, cv::INTER_NEAREST);
  aloe.truth_px.create(truth_half.size(), CV_32FC1);
  for (int v = 0; v < truth_half.rows; ++v) {
    for (int u = 0; u < truth_half.cols; ++u) {
      const uint8_t g = truth_half.at<uint8_t>(v, u);
      aloe.truth_px.at<float>(v, u) = g == 0 ? kInvalidDisparity : g / 2.0f;
    }
  }
  return aloe;
}

struct AloeCase {
  DisparityMethod method;
  double max_bad_rate;  // measured + margin
  double min_density;   // measured - margin
};

class AloeTest : public ::testing::TestWithParam<AloeCase> {};

TEST_P(AloeTest, BadPixelRateAndDensityHoldTheMeasuredFigures) {
  const HalfAloe aloe = LoadHalfAloe();
  ASSERT_FALSE(aloe.left.empty()) << "the Middlebury Aloe pair is missing from " << kAloeDir
                                  << ": install Debian's opencv-doc (scripts/install-deps.sh)";
  ASSERT_EQ(aloe.left.size(), cv::Size(641, 555));
  DisparityOptions options;
  options.method = GetParam().method;
  options.num_disparities = 112;  // ground truth 21.5..105.5 px at half size
  DisparityMatcher matcher(options);
  const cv::Mat disparity = matcher.Compute(aloe.left, aloe.right);
  const DisparityErrorStats stats = EvaluateDisparity(disparity, aloe.truth_px);
  RecordProperty("bad_rate", std::to_string(stats.bad_rate));
  RecordProperty("density", std::to_string(stats.density));
  std::printf("%s: bad-2.0 %.4f  density %.4f  mean |error| %.3f px  (%ld of %ld pixels)\n",
              DisparityMethodName(options.method), stats.bad_rate, stats.density,
              stats.mean_abs_error_px, stats.estimated_pixels, stats.ground_truth_pixels);
  EXPECT_GT(stats.ground_truth_pixels, 300000);
  EXPECT_LE(stats.bad_rate, GetParam().max_bad_rate);
  EXPECT_GE(stats.density, GetParam().min_density);
}

// Measured with the defaults of disparity.h (OpenCV 4.6, Debian 12); docs/stereo.md.
INSTANTIATE_TEST_SUITE_P(
    Methods, AloeTest,
    ::testing::Values(AloeCase{DisparityMethod::kBlockMatching, 0.0173 + 0.005, 0.6281 - 0.01},
                      AloeCase{DisparityMethod::kSemiGlobal, 0.0332 + 0.005, 0.7194 - 0.01}),
    [](const auto& info) { return DisparityMethodName(info.param.method); });

}  // namespace
}  // namespace stereodet
