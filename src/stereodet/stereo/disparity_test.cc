#include "stereodet/stereo/disparity.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "stereodet/geometry/calibration.h"
#include "stereodet/stereo/planar_scene.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/fuzz_corpus.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// A textured wall 20 m ahead filling a 1242 x 120 view (the ground 100 m down): its disparity is
// the non-integer f b / 20 everywhere.
PlanarSceneOptions TexturedWallAt20m() {
  PlanarSceneOptions options;
  options.width_px = 1242;
  options.height_px = 120;
  options.camera_height_m = 100;
  options.wall_depth_m = 20;
  options.texture_scale_m = 0.02;
  return options;
}

// A smooth random texture: noise blurred so that block matching has structure at several scales.
cv::Mat Texture(int rows, int cols, unsigned seed) {
  cv::Mat noise(rows, cols, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat smooth;
  cv::GaussianBlur(noise, smooth, cv::Size(5, 5), 1.0);
  cv::normalize(smooth, smooth, 0, 255, cv::NORM_MINMAX);
  return smooth;
}

// Fraction of `disparity` pixels in columns >= first_col that are valid and within `tolerance` of
// `expected`, and the fraction that are valid.
std::pair<double, double> AccuracyAndDensity(const cv::Mat& disparity, double expected,
                                             double tolerance, int first_col) {
  long valid = 0, close = 0, total = 0;
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = first_col; u < disparity.cols; ++u) {
      ++total;
      const float d = disparity.at<float>(v, u);
      if (!IsValidDisparity(d)) continue;
      ++valid;
      close += std::abs(d - expected) <= tolerance;
    }
  }
  return {valid > 0 ? static_cast<double>(close) / valid : 0.0, static_cast<double>(valid) / total};
}

TEST(DisparityOptionsTest, RejectsBadSettings) {
  DisparityOptions options;
  EXPECT_NO_THROW(options.Check());
  options.num_disparities = 100;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = {};
  options.bm.block_size = 14;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = {};
  options.method = DisparityMethod::kSemiGlobal;
  options.sgbm.p2_per_pixel = options.sgbm.p1_per_pixel;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = {};
  options.min_disparity = -16;
  EXPECT_THROW(DisparityMatcher{options}, std::invalid_argument);
}

// The match-scale settings of DisparityOptions::AtMatchScale, by hand from its documented rules.
TEST(DisparityOptionsTest, MatchScaleScalesTheSearchAndTheWindows) {
  DisparityOptions options;
  EXPECT_EQ(options.match_scale, 1.0);  // the documented default: full resolution
  EXPECT_EQ(options.MatchSize({1242, 375}), cv::Size(1242, 375));
  options.match_scale = 0.5;
  EXPECT_NO_THROW(options.Check());
  EXPECT_EQ(options.MatchSize({1242, 375}), cv::Size(621, 188));  // round(187.5) = 188
  EXPECT_EQ(options.MatchSize({1241, 376}), cv::Size(621, 188));
  const DisparityOptions half = options.AtMatchScale();
  EXPECT_EQ(half.match_scale, 1.0);
  EXPECT_EQ(half.num_disparities, 64);  // 128 x 0.5
  EXPECT_EQ(half.min_disparity, 0);
  EXPECT_EQ(half.bm.block_size, 5);       // odd(5.5) = 5
  EXPECT_EQ(half.bm.prefilter_size, 5);   // odd(4.5) = 5
  EXPECT_EQ(half.sgbm.block_size, 3);     // odd(2.5) = 3
  EXPECT_EQ(half.speckle_window_px, 25);  // 100 x 0.5^2
  EXPECT_EQ(half.speckle_range_px, 1);    // 2 x 0.5
  EXPECT_EQ(half.uniqueness_ratio, 15);   // kept
  EXPECT_EQ(half.left_right_max_diff_px, 1);
  EXPECT_EQ(half.bm.texture_threshold, 10);
  EXPECT_EQ(half.wls.depth_discontinuity_radius, 2);
  EXPECT_EQ(half.wls.lrc_threshold, 12);
  EXPECT_EQ(half.sgbm.P1(), 8 * 1 * 3 * 3);  // the per-pixel rule follows the smaller block
  // Rounding: the search is rounded up to a multiple of 16; blocks stay odd and >= 5 for BM.
  options.num_disparities = 112;  // 56 -> 64
  options.min_disparity = 5;      // 2.5 -> 2
  options.bm.block_size = 21;     // 10.5 -> 11
  options.speckle_range_px = 1;   // 0.5 -> 1 (at least 1 where it was)
  EXPECT_EQ(options.AtMatchScale().num_disparities, 64);
  EXPECT_EQ(options.AtMatchScale().min_disparity, 2);
  EXPECT_EQ(options.AtMatchScale().bm.block_size, 11);
  EXPECT_EQ(options.AtMatchScale().speckle_range_px, 1);
  options.match_scale = 0.1;  // the smallest: 112 x 0.1 = 11.2 -> 16, block 2.1 -> 5
  EXPECT_EQ(options.AtMatchScale().num_disparities, 16);
  EXPECT_EQ(options.AtMatchScale().bm.block_size, 5);
  EXPECT_NO_THROW(options.Check());
  // At 1 nothing changes.
  DisparityOptions full;
  full.num_disparities = 96;
  full.bm.block_size = 15;
  EXPECT_EQ(full.AtMatchScale().num_disparities, 96);
  EXPECT_EQ(full.AtMatchScale().bm.block_size, 15);
  EXPECT_EQ(full.AtMatchScale().speckle_window_px, 100);
}

TEST(DisparityOptionsTest, RejectsAMatchScaleOutsideItsRange) {
  for (double scale : {0.0, -0.5, 0.05, 1.01, 2.0, std::nan(""), HUGE_VAL}) {
    DisparityOptions options;
    options.match_scale = scale;
    EXPECT_THROW(options.Check(), std::invalid_argument) << scale;
    EXPECT_THROW(DisparityMatcher{options}, std::invalid_argument) << scale;
  }
}

// UpsampleDisparity by hand: each output pixel takes the value under its centre, times 2.
TEST(DisparityTest, UpsampleDisparityScalesValuesAndKeepsInvalid) {
  const cv::Mat small = (cv::Mat_<float>(2, 3) << 1.0f, kInvalidDisparity, 2.5f, 3.0f, 4.0f, 0.0f);
  const cv::Mat full = UpsampleDisparity(small, {6, 4});
  ASSERT_EQ(full.size(), cv::Size(6, 4));
  for (int v = 0; v < 4; ++v) {
    for (int u = 0; u < 6; ++u) {
      const float expected = small.at<float>(v / 2, u / 2);
      const float got = full.at<float>(v, u);
      if (IsValidDisparity(expected)) {
        EXPECT_FLOAT_EQ(got, 2.0f * expected) << v << "," << u;
      } else {
        EXPECT_FALSE(IsValidDisparity(got)) << v << "," << u;
      }
    }
  }
  EXPECT_EQ(UpsampleDisparity(small, small.size()).data, small.data);  // shared at its size
  EXPECT_THROW(UpsampleDisparity(cv::Mat(2, 2, CV_16SC1), {4, 4}), std::invalid_argument);
}

// A wall at a known depth fills the view: matched at half the size, the disparity (in full-size
// px) is the true one within 1 px (0.5 match-scale px) at 95% of the pixels; at full size it is
// within 0.3 px at 98% (ShiftedTextureTest). Measured: the 5 x 5 block of half scale (from 11) has
// a sub-pixel spread of about +-0.75 full-size px on this texture, the full-size 11 x 11 of
// +-0.25 px.
TEST(DisparityTest, HalfScaleMatchingRecoversAWallAtAKnownDepth) {
  const PlanarSceneOptions scene_options = TexturedWallAt20m();
  const Calibration calib = KittiLikeCalibration();
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  const double expected = geometry.DisparityFromDepth(20.0);
  // (f b / z ignores KITTI's 16 um z offset between the cameras: 0.003 px here.)
  EXPECT_NEAR(scene.disparity_px.at<float>(60, 600), expected, 0.01);
  DisparityOptions options;
  options.num_disparities = 32;
  options.match_scale = 0.5;
  DisparityMatcher matcher(options);
  EXPECT_EQ(matcher.matching_options().num_disparities, 16);
  const cv::Mat disparity = matcher.Compute(scene.left_bgr, scene.right_bgr);
  ASSERT_EQ(disparity.size(), scene.left_bgr.size());
  const auto [accuracy, density] = AccuracyAndDensity(disparity, expected, 1.0, 64);
  EXPECT_GT(density, 0.75);
  EXPECT_GT(accuracy, 0.95) << "expected " << expected;
  // The fixed-point entry takes the images at the match size, and refuses the full size's width
  // only when the search does not fit (here it does: 16 < 621).
  const cv::Mat grey = ToGrey(scene.left_bgr);
  EXPECT_EQ(matcher
                .ComputeFixedPoint(ResizeForMatching(grey, {621, 60}),
                                   ResizeForMatching(ToGrey(scene.right_bgr), {621, 60}))
                .size(),
            cv::Size(621, 60));
}

// The size check applies to the match-scale image and says so.
TEST(DisparityTest, ImageFitCheckUsesTheMatchSize) {
  DisparityOptions options;
  options.num_disparities = 64;
  EXPECT_NO_THROW(CheckImageFitsMatcher(options, {100, 40}, "a.png"));
  options.match_scale = 0.5;  // 50 x 20 px: 32 disparities fit, a 5 px block fits
  EXPECT_NO_THROW(CheckImageFitsMatcher(options, {100, 40}, "a.png"));
  options.match_scale = 0.25;  // 25 x 10 px: 16 disparities fit, a 5 px block fits
  EXPECT_NO_THROW(CheckImageFitsMatcher(options, {100, 40}, "a.png"));
  options.match_scale = 0.1;  // 10 x 4 px: the block does not
  try {
    CheckImageFitsMatcher(options, {100, 40}, "a.png");
    ADD_FAILURE() << "no throw";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("a.png"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("--match-scale"));
  }
}

TEST(DisparityOptionsTest, ParsesMethodNames) {
  EXPECT_EQ(ParseDisparityMethod("bm"), DisparityMethod::kBlockMatching);
  EXPECT_EQ(ParseDisparityMethod("sgbm"), DisparityMethod::kSemiGlobal);
  EXPECT_STREQ(DisparityMethodName(DisparityMethod::kSemiGlobal), "sgbm");
  for (DisparityMethod method : {DisparityMethod::kBlockMatching, DisparityMethod::kSemiGlobal}) {
    EXPECT_EQ(ParseDisparityMethod(DisparityMethodName(method)), method);
  }
  EXPECT_EQ(ParseDisparityMethod("BM"), std::nullopt);
}

TEST(DisparityOptionsTest, ChecksTheRangeOfEveryOpenCvSetting) {
  auto rejects = [](auto change) {
    DisparityOptions options;
    change(options);
    return [&] {
      try {
        options.Check();
        return false;
      } catch (const std::invalid_argument&) {
        return true;
      }
    }();
  };
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.num_disparities = 100000; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.min_disparity = 5000; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.uniqueness_ratio = 101; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.speckle_range_px = -1; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.left_right_max_diff_px = -2; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.bm.prefilter_cap = 64; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) { o.bm.texture_threshold = -1; }));
  auto sgbm = [](auto change) {
    return [change](DisparityOptions& o) {
      o.method = DisparityMethod::kSemiGlobal;
      change(o.sgbm);
    };
  };
  EXPECT_TRUE(rejects(sgbm([](SemiGlobalOptions& o) { o.prefilter_cap = 1024; })));
  EXPECT_TRUE(rejects(sgbm([](SemiGlobalOptions& o) { o.p1 = 900; })));  // P1 900 > P2 800
  EXPECT_TRUE(rejects(sgbm([](SemiGlobalOptions& o) { o.p2_per_pixel = 2000000000; })));
  EXPECT_FALSE(rejects(sgbm([](SemiGlobalOptions& o) { o.p1 = 100; })));
  // The WLS settings are checked only when the filter is on.
  EXPECT_FALSE(rejects([](DisparityOptions& o) { o.wls.lambda = -1; }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) {
    o.wls.enabled = true;
    o.wls.lambda = -1;
  }));
  EXPECT_TRUE(rejects([](DisparityOptions& o) {
    o.wls.enabled = true;
    o.wls.sigma_color = std::nan("");
  }));
}

TEST(DisparityOptionsTest, SgbmPenaltiesFollowOpenCvsRule) {
  SemiGlobalOptions o;  // block 5: P1 = 8 x 25, P2 = 32 x 25
  EXPECT_EQ(o.P1(), 200);
  EXPECT_EQ(o.P2(), 800);
  o.colour = true;  // OpenCV's 8 x channels x block^2
  EXPECT_EQ(o.P1(), 600);
  EXPECT_EQ(o.P2(), 2400);
  o.p1 = 50;
  o.p2 = 70;
  EXPECT_EQ(o.P1(), 50);
  EXPECT_EQ(o.P2(), 70);
}

TEST(DisparityOptionsTest, ParsesSgbmModeNames) {
  for (SgbmMode mode : {SgbmMode::kSgbm, SgbmMode::kHh, SgbmMode::kSgbm3Way, SgbmMode::kHh4}) {
    EXPECT_EQ(ParseSgbmMode(SgbmModeName(mode)), mode);
  }
  EXPECT_EQ(ParseSgbmMode("HH"), std::nullopt);
  EXPECT_STREQ(SgbmModeName(SgbmMode::kSgbm3Way), "sgbm3way");
}

// SGBM on the colour pair, every SGBM mode, and the WLS filter all recover a whole-pixel shift; WLS
// fills BM's holes.
TEST(DisparityTest, ColourModesAndWlsRecoverAShift) {
  const int shift = 20;
  cv::Mat wide_bgr;
  cv::merge(std::vector<cv::Mat>{Texture(120, 380, 1), Texture(120, 380, 2), Texture(120, 380, 3)},
            wide_bgr);
  const cv::Mat left = wide_bgr.colRange(0, 360).clone();
  const cv::Mat right = wide_bgr.colRange(shift, 360 + shift).clone();
  for (SgbmMode mode : {SgbmMode::kSgbm, SgbmMode::kHh, SgbmMode::kSgbm3Way, SgbmMode::kHh4}) {
    for (bool colour : {false, true}) {
      DisparityOptions options;
      options.method = DisparityMethod::kSemiGlobal;
      options.num_disparities = 48;
      options.sgbm.mode = mode;
      options.sgbm.colour = colour;
      DisparityMatcher matcher(options);
      const auto [accuracy, density] =
          AccuracyAndDensity(matcher.Compute(left, right), shift, 0.25, 64);
      EXPECT_GT(density, 0.85) << SgbmModeName(mode) << " colour " << colour;
      EXPECT_GT(accuracy, 0.98) << SgbmModeName(mode) << " colour " << colour;
    }
  }
  DisparityOptions bm_options;
  bm_options.num_disparities = 48;
  DisparityOptions wls_options = bm_options;
  wls_options.wls.enabled = true;
  // A textureless patch of the scene, where BM finds nothing.
  cv::Mat flat = wide_bgr.clone();
  flat(cv::Rect(150, 40, 60, 40)).setTo(cv::Scalar(128, 128, 128));
  const cv::Mat flat_left = flat.colRange(0, 360).clone();
  const cv::Mat flat_right = flat.colRange(shift, 360 + shift).clone();
  const cv::Mat bm = DisparityMatcher(bm_options).Compute(flat_left, flat_right);
  const cv::Mat wls = DisparityMatcher(wls_options).Compute(flat_left, flat_right);
  // Inside the filter's region of interest (the matcher's window margins and the search range left
  // out: 5 rows top and bottom, 5 columns at the right, 48 + 5 at the left).
  const cv::Rect inside(64, 8, 360 - 64 - 8, 120 - 16);
  const double bm_density = AccuracyAndDensity(bm(inside), shift, 0.25, 0).second;
  const auto [wls_accuracy, wls_density] = AccuracyAndDensity(wls(inside), shift, 0.5, 0);
  EXPECT_GT(wls_density, bm_density);
  EXPECT_GT(wls_density, 0.99);
  EXPECT_GT(wls_accuracy, 0.95);
  // Colour SGBM needs colour images: grey ones are refused with the reason.
  DisparityOptions colour;
  colour.method = DisparityMethod::kSemiGlobal;
  colour.sgbm.colour = true;
  colour.num_disparities = 48;
  DisparityMatcher matcher(colour);
  EXPECT_THROW(matcher.ComputeFixedPoint(ToGrey(left), ToGrey(right)), std::invalid_argument);
}

TEST(DisparityTest, ValidityConvention) {
  EXPECT_FALSE(IsValidDisparity(kInvalidDisparity));
  EXPECT_FALSE(IsValidDisparity(0.0f));
  EXPECT_FALSE(IsValidDisparity(std::nanf("")));
  EXPECT_TRUE(IsValidDisparity(0.0625f));
}

TEST(DisparityTest, FixedPointConversionMarksInvalid) {
  cv::Mat fixed = (cv::Mat_<int16_t>(1, 4) << -16, 0, 1, 328);
  const cv::Mat disparity = DisparityFromFixedPoint(fixed);
  EXPECT_EQ(disparity.at<float>(0, 0), kInvalidDisparity);
  EXPECT_EQ(disparity.at<float>(0, 1), kInvalidDisparity);
  EXPECT_FLOAT_EQ(disparity.at<float>(0, 2), 1.0f / 16);
  EXPECT_FLOAT_EQ(disparity.at<float>(0, 3), 20.5f);
}

// A texture shifted by a whole number of pixels: right(u) = left(u + 20), so the disparity is 20.
class ShiftedTextureTest : public ::testing::TestWithParam<DisparityMethod> {};

TEST_P(ShiftedTextureTest, RecoversIntegerShift) {
  const int shift = 20;
  const cv::Mat wide = Texture(120, 360 + shift, 7);
  const cv::Mat left = wide.colRange(0, 360).clone();
  const cv::Mat right = wide.colRange(shift, 360 + shift).clone();
  DisparityOptions options;
  options.method = GetParam();
  options.num_disparities = 48;
  DisparityMatcher matcher(options);
  const cv::Mat disparity = matcher.Compute(left, right);
  ASSERT_EQ(disparity.type(), CV_32FC1);
  ASSERT_EQ(disparity.size(), left.size());
  const auto [accuracy, density] = AccuracyAndDensity(disparity, shift, 0.25, 64);
  EXPECT_GT(density, 0.85);
  EXPECT_GT(accuracy, 0.98);
  // The left-most columns cannot be matched and must be marked, not left at 0.
  EXPECT_EQ(disparity.at<float>(60, 5), kInvalidDisparity);
}

TEST_P(ShiftedTextureTest, SubPixelOnRenderedWall) {
  // A wall 20 m ahead fills the whole view (the ground is 100 m down): its disparity is the
  // non-integer f b / 20 everywhere, so the matcher's sub-pixel interpolation is exercised.
  const PlanarSceneOptions scene_options = TexturedWallAt20m();
  const PlanarScene scene = RenderPlanarScene(KittiLikeCalibration(), scene_options);
  const double expected = scene.disparity_px.at<float>(60, 600);
  DisparityOptions options;
  options.method = GetParam();
  options.num_disparities = 32;
  DisparityMatcher matcher(options);
  const cv::Mat disparity = matcher.Compute(scene.left_bgr, scene.right_bgr);
  // SGBM's fixed-point sub-pixel fit "locks" towards whole pixels a little more than BM's: 0.3 px.
  const auto [accuracy, density] = AccuracyAndDensity(disparity, expected, 0.3, 64);
  EXPECT_GT(density, 0.8);
  EXPECT_GT(accuracy, 0.98) << "expected " << expected;
  EXPECT_NE(std::round(expected), expected);
}

INSTANTIATE_TEST_SUITE_P(Methods, ShiftedTextureTest,
                         ::testing::Values(DisparityMethod::kBlockMatching,
                                           DisparityMethod::kSemiGlobal),
                         [](const auto& info) { return DisparityMethodName(info.param); });

TEST(DisparityTest, RejectsMismatchedImages) {
  DisparityMatcher matcher;
  cv::Mat a(100, 200, CV_8UC1, cv::Scalar(0)), b(100, 201, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(matcher.Compute(a, b), std::invalid_argument);
  cv::Mat f(100, 200, CV_32FC1);
  EXPECT_THROW(matcher.Compute(f, f), std::invalid_argument);
}

TEST(DisparityTest, RejectsASearchRangeAsWideAsTheImage) {
  // 128 disparities (the default) leave 72 columns of a 200-px image; 192 leave 8, 208 none.
  cv::Mat image(100, 200, CV_8UC1, cv::Scalar(0));
  DisparityOptions options;
  EXPECT_NO_THROW(DisparityMatcher(options).Compute(image, image));
  options.num_disparities = 192;
  EXPECT_NO_THROW(DisparityMatcher(options).Compute(image, image));
  options.num_disparities = 208;
  try {
    DisparityMatcher(options).Compute(image, image);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("(0 + 208) must be less than the image width 200"));
  }
  options.num_disparities = 100000;
  EXPECT_THROW(DisparityMatcher(options).Compute(image, image), std::invalid_argument);
}

TEST(KittiDisparityFormatTest, RoundTripsWithinQuantization) {
  const TestTempDir temp;
  const fs::path& dir = temp.path();
  cv::Mat disparity = (cv::Mat_<float>(2, 3) << 0.5f, 100.25f, kInvalidDisparity,  //
                       0.001f, 255.99f, 300.0f);
  WriteKittiDisparity(dir / "d.png", disparity);
  const cv::Mat raw = cv::imread((dir / "d.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.at<uint16_t>(0, 0), 128);
  EXPECT_EQ(raw.at<uint16_t>(0, 1), 25664);
  EXPECT_EQ(raw.at<uint16_t>(0, 2), 0);
  EXPECT_EQ(raw.at<uint16_t>(1, 0), 1);  // tiny but valid: never written as "invalid"
  EXPECT_EQ(raw.at<uint16_t>(1, 2), 65535);
  const cv::Mat back = ReadKittiDisparity(dir / "d.png");
  EXPECT_FLOAT_EQ(back.at<float>(0, 0), 0.5f);
  EXPECT_FLOAT_EQ(back.at<float>(0, 1), 100.25f);
  EXPECT_EQ(back.at<float>(0, 2), kInvalidDisparity);
  EXPECT_NEAR(back.at<float>(1, 1), 255.99f, 1.0 / 256);
  // No temporary left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
}

TEST(KittiDisparityFormatTest, RejectsWrongFiles) {
  const TestTempDir temp;
  const fs::path& dir = temp.path();
  EXPECT_THROW(ReadKittiDisparity(dir / "missing.png"), std::runtime_error);
  cv::imwrite((dir / "eight.png").string(), cv::Mat(4, 4, CV_8UC1, cv::Scalar(3)));
  EXPECT_THROW(ReadKittiDisparity(dir / "eight.png"), std::runtime_error);
}

TEST(EvaluateDisparityTest, HandComputedRates) {
  const float x = kInvalidDisparity;
  cv::Mat truth = (cv::Mat_<float>(1, 6) << 10, 10, 100, 100, x, 50);
  cv::Mat estimate = (cv::Mat_<float>(1, 6) << 10.5f, 13.5f, 104, 106, 7, x);
  const DisparityErrorStats stats = EvaluateDisparity(estimate, truth);
  EXPECT_EQ(stats.ground_truth_pixels, 5);
  EXPECT_EQ(stats.estimated_pixels, 4);
  EXPECT_DOUBLE_EQ(stats.density, 0.8);
  EXPECT_DOUBLE_EQ(stats.bad_rate, 0.75);  // errors 0.5, 3.5, 4, 6: three over 2 px
  EXPECT_DOUBLE_EQ(stats.d1_rate, 0.5);    // 3.5 (> 3 and > 0.5) and 6 (> 3 and > 5); 4 < 5
  EXPECT_DOUBLE_EQ(stats.mean_abs_error_px, (0.5 + 3.5 + 4 + 6) / 4);
  // KITTI's D1-all: the two outliers and the ground-truth pixel without an estimate, of 5.
  EXPECT_EQ(stats.d1_outlier_pixels, 2);
  EXPECT_EQ(stats.bad_pixels, 3);
  EXPECT_DOUBLE_EQ(stats.d1_all_rate, 3.0 / 5.0);
}

TEST(EvaluateDisparityTest, D1AllCountsEveryMissingEstimate) {
  const float x = kInvalidDisparity;
  const cv::Mat truth = (cv::Mat_<float>(1, 4) << 20, 20, 20, 20);
  const cv::Mat none = (cv::Mat_<float>(1, 4) << x, x, x, x);
  const DisparityErrorStats empty = EvaluateDisparity(none, truth);
  EXPECT_DOUBLE_EQ(empty.d1_all_rate, 1.0);  // nothing estimated: every pixel is an error
  EXPECT_DOUBLE_EQ(empty.d1_rate, 0.0);      // no estimated pixel to rate
  EXPECT_DOUBLE_EQ(empty.density, 0.0);
  const cv::Mat exact = truth.clone();
  EXPECT_DOUBLE_EQ(EvaluateDisparity(exact, truth).d1_all_rate, 0.0);
}

TEST(EvaluateDisparityTest, PoolingEqualsOneEvaluationOfTheConcatenation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(1, 60), noise(-6, 6), coin(0, 1);
  cv::Mat truth(3, 40, CV_32FC1), estimate(3, 40, CV_32FC1);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 40; ++u) {
      truth.at<float>(v, u) = coin(rng) < 0.2f ? kInvalidDisparity : value(rng);
      estimate.at<float>(v, u) =
          coin(rng) < 0.3f ? kInvalidDisparity : std::max(0.5f, truth.at<float>(v, u) + noise(rng));
    }
  }
  std::vector<DisparityErrorStats> rows;
  for (int v = 0; v < 3; ++v) rows.push_back(EvaluateDisparity(estimate.row(v), truth.row(v)));
  const DisparityErrorStats pooled = PoolDisparityErrors(rows);
  const DisparityErrorStats whole = EvaluateDisparity(estimate, truth);
  EXPECT_EQ(pooled.ground_truth_pixels, whole.ground_truth_pixels);
  EXPECT_EQ(pooled.estimated_pixels, whole.estimated_pixels);
  EXPECT_EQ(pooled.d1_outlier_pixels, whole.d1_outlier_pixels);
  EXPECT_DOUBLE_EQ(pooled.d1_all_rate, whole.d1_all_rate);
  EXPECT_DOUBLE_EQ(pooled.d1_rate, whole.d1_rate);
  EXPECT_DOUBLE_EQ(pooled.bad_rate, whole.bad_rate);
  EXPECT_NEAR(pooled.mean_abs_error_px, whole.mean_abs_error_px, 1e-12);
  EXPECT_GT(whole.d1_all_rate, whole.d1_rate);  // the holes count in D1-all
}

// The disparity fuzzer's corpus (fuzz/disparity_fuzzer.cc), replayed: each PNG decodes to valid
// disparities or throws std::runtime_error naming the file (a header claiming 100000x100000 px,
// a truncated file, an 8-bit or colour image); never a crash or an OpenCV assertion.
TEST(DisparityTest, FuzzCorpusInputsDecodeOrThrowNamingTheFile) {
  const std::vector<std::filesystem::path> files = FuzzCorpusFiles("disparity");
  ASSERT_GE(files.size(), 4u) << "the disparity corpus is missing";
  int decoded = 0, rejected = 0;
  for (const std::filesystem::path& path : files) {
    SCOPED_TRACE(path.filename().string());
    const std::string bytes = ReadFile(path);
    try {
      const cv::Mat disparity = DecodeKittiDisparity(bytes, path.string());
      ASSERT_EQ(disparity.type(), CV_32FC1);
      EXPECT_EQ(cv::norm(ReadKittiDisparity(path), disparity, cv::NORM_INF), 0.0);
      for (int v = 0; v < disparity.rows; ++v) {
        for (int u = 0; u < disparity.cols; ++u) {
          const float d = disparity.at<float>(v, u);
          EXPECT_TRUE(!IsValidDisparity(d) || (d > 0.0f && d < 256.0f)) << d;
        }
      }
      ++decoded;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
      ++rejected;
    }
  }
  EXPECT_GT(decoded, 0);
  EXPECT_GT(rejected, 0);
}

}  // namespace
}  // namespace stereodet
