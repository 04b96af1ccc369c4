#include "stereodet/stereo/stereo_encoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "stereodet/stereo/planar_scene.h"
#include "stereodet/stereo/rgbh.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

struct PointAlignment {
  size_t paired = 0;  // points of a with a partner in b, in order
  size_t only_in_a = 0, only_in_b = 0;
  size_t reflectance_mismatches = 0;  // pairs whose reflectance differs
};

bool Close(const VeloPoint& p, const VeloPoint& q, double tolerance) {
  return std::abs(p.x - q.x) <= tolerance && std::abs(p.y - q.y) <= tolerance &&
         std::abs(p.z - q.z) <= tolerance;
}

// Pairs the points of two clouds in the same order (a merge: when a[i] and b[j] differ, the nearer
// of the next points of a that matches b[j], or of b that matches a[i], resynchronises; a point
// with no partner within kLookahead is counted unpaired). Exhaustive: every point is looked at.
PointAlignment AlignPointClouds(const std::vector<VeloPoint>& a, const std::vector<VeloPoint>& b,
                                double tolerance) {
  constexpr size_t kLookahead = 8;
  PointAlignment result;
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (Close(a[i], b[j], tolerance)) {
      ++result.paired;
      if (a[i].reflectance != b[j].reflectance) ++result.reflectance_mismatches;
      ++i, ++j;
      continue;
    }
    size_t skip_a = 0, skip_b = 0;
    for (size_t k = 1; k <= kLookahead && skip_a == 0 && skip_b == 0; ++k) {
      if (i + k < a.size() && Close(a[i + k], b[j], tolerance)) skip_a = k;
      if (j + k < b.size() && Close(a[i], b[j + k], tolerance)) skip_b = k;
    }
    if (skip_a == 0 && skip_b == 0) skip_a = skip_b = 1;  // differ in value: unpaired both
    if (skip_a != 0 && skip_b != 0 && skip_a != skip_b) skip_b = 0;  // both found: one side
    i += skip_a, j += skip_b;
    result.only_in_a += skip_a, result.only_in_b += skip_b;
  }
  result.only_in_a += a.size() - i;
  result.only_in_b += b.size() - j;
  return result;
}

TEST(StereoEncoderTest, AlignPointCloudsCountsWhatDiffers) {
  std::vector<VeloPoint> a;
  for (int i = 0; i < 100; ++i) a.push_back({static_cast<float>(i), 1.0f, 2.0f, 0.5f});
  EXPECT_EQ(AlignPointClouds(a, a, 1e-3).paired, 100u);
  std::vector<VeloPoint> b = a;
  b.erase(b.begin() + 40);      // one dropped
  b[70].y += 0.1f;              // one wrong
  b[80].reflectance = 0.25f;    // one wrong reflectance
  b.push_back({500, 0, 0, 0});  // one extra at the end
  const PointAlignment aligned = AlignPointClouds(a, b, 1e-3);
  EXPECT_EQ(aligned.paired, 98u);
  EXPECT_EQ(aligned.only_in_a, 2u);  // a[40] and a[71]
  EXPECT_EQ(aligned.only_in_b, 2u);  // b[70] and the extra
  EXPECT_EQ(aligned.reflectance_mismatches, 1u);
}

// The fused encoder must agree with the separate reference functions.
TEST(StereoEncoderTest, MatchesTheReferenceFunctions) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.ground_pitch_deg = 1.0;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  StereoOptions options;
  StereoEncoder encoder(options);
  StageTimes times;
  const StereoEncoding encoding =
      encoder.Encode(scene.left_bgr, scene.right_bgr, geometry,
                     {.rgbh = true, .depth = true, .points = true}, &times);
  ASSERT_TRUE(encoding.ground.fitted) << encoding.ground.reason;

  // Disparity: exactly the matcher's.
  DisparityMatcher matcher(options.disparity);
  const cv::Mat disparity = matcher.Compute(scene.left_bgr, scene.right_bgr);
  EXPECT_EQ(cv::norm(disparity, encoding.disparity_px, cv::NORM_INF), 0.0);

  // Height and depth codes: equal but for rare rounding ties (float vs double order of operations).
  const cv::Mat height = HeightFromDisparity(disparity, geometry, encoding.ground.plane);
  const cv::Mat height_code = QuantizeHeight(height, options.height);
  const cv::Mat depth_code = QuantizeDepth(DepthFromDisparity(disparity, geometry), options.depth);
  cv::Mat height_diff, depth_diff;
  cv::absdiff(height_code, encoding.height_code, height_diff);
  cv::absdiff(depth_code, encoding.depth_code, depth_diff);
  double max_height_diff, max_depth_diff;
  cv::minMaxLoc(height_diff, nullptr, &max_height_diff);
  cv::minMaxLoc(depth_diff, nullptr, &max_depth_diff);
  EXPECT_LE(max_height_diff, 1);
  EXPECT_LE(max_depth_diff, 1);
  EXPECT_LT(cv::countNonZero(height_diff), height_diff.total() / 1000);
  // Reserved zero exactly where there is no disparity.
  for (int v = 0; v < disparity.rows; v += 5) {
    for (int u = 0; u < disparity.cols; u += 5) {
      ASSERT_EQ(encoding.height_code.at<uint16_t>(v, u) == 0,
                !IsValidDisparity(disparity.at<float>(v, u)));
    }
  }

  // RGB-H: the packing of the left image with those codes.
  const UnpackedRgbh unpacked = UnpackRgbh(encoding.rgbh);
  EXPECT_EQ(cv::norm(unpacked.height_code, encoding.height_code, cv::NORM_INF), 0.0);
  cv::Mat floor5(scene.left_bgr.size(), CV_8UC3);
  for (int i = 0; i < static_cast<int>(scene.left_bgr.total() * 3); ++i) {
    floor5.data[i] = scene.left_bgr.data[i] >> 3;
  }
  EXPECT_EQ(cv::norm(unpacked.bgr5, floor5, cv::NORM_INF), 0.0);

  // Point cloud: the reference's, in the same order.
  const std::vector<VeloPoint> reference = StereoPointCloud(
      disparity, ToGrey(scene.left_bgr), geometry, encoding.ground.plane, options.points);
  ASSERT_GT(reference.size(), 10000u);
  // Points whose height sits on a truncation bound may be kept by one and dropped by the other:
  // align the two clouds (both in pixel order) and compare every point, allowing a handful of
  // points on either side without a partner. A point that differs in value is one unpaired on each
  // side, so a wrong coordinate anywhere but in a handful of points fails.
  const PointAlignment aligned = AlignPointClouds(reference, encoding.points, 1e-3);
  EXPECT_LE(aligned.only_in_a, 5u);
  EXPECT_LE(aligned.only_in_b, 5u);
  EXPECT_GE(aligned.paired + 5, reference.size());
  EXPECT_EQ(aligned.reflectance_mismatches, 0u);
  const auto stages = times.Snapshot();
  for (const char* stage : {"grey", "disparity", "ground", "encode"}) {
    EXPECT_EQ(stages.count(stage), 1u) << stage;
  }
}

TEST(StereoEncoderTest, BlurModes) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.height_px = 200;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  StereoOptions sharp_options;
  const StereoEncoding sharp =
      StereoEncoder(sharp_options).Encode(scene.left_bgr, scene.right_bgr, geometry);

  StereoOptions image_options;
  image_options.blur = {.sigma_px = 2.0, .mode = BlurMode::kNetworkImage};
  const StereoEncoding image_only =
      StereoEncoder(image_options).Encode(scene.left_bgr, scene.right_bgr, geometry);
  // The network image is blurred, the stereo is not.
  EXPECT_GT(cv::norm(image_only.network_image, scene.left_bgr, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(image_only.disparity_px, sharp.disparity_px, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(image_only.height_code, sharp.height_code, cv::NORM_INF), 0.0);

  StereoOptions both_options;
  both_options.blur = {.sigma_px = 2.0, .mode = BlurMode::kBothBeforeMatching};
  const StereoEncoding both =
      StereoEncoder(both_options).Encode(scene.left_bgr, scene.right_bgr, geometry);
  EXPECT_EQ(cv::norm(both.network_image, image_only.network_image, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(both.disparity_px, sharp.disparity_px, cv::NORM_INF), 0.0);

  StereoOptions bad;
  bad.blur.sigma_px = -1;
  EXPECT_THROW(StereoEncoder{bad}, std::invalid_argument);
}

// Every setting of StereoSettingsJson reads back, and a file without a setting reads as the default
// given (an older model.json or stereo.json).
TEST(StereoSettingsJsonTest, RoundTripsAndDefaultsWhatIsMissing) {
  StereoOptions options;
  options.disparity.method = DisparityMethod::kSemiGlobal;
  options.disparity.uniqueness_ratio = 7;
  options.disparity.bm.xsobel_prefilter = false;
  options.disparity.sgbm.mode = SgbmMode::kHh4;
  options.disparity.sgbm.colour = true;
  options.disparity.sgbm.p1 = 300;
  options.disparity.wls.enabled = true;
  options.disparity.wls.lambda = 1234.5;
  options.ground.max_tilt_deg = 4.5;
  options.height.max_m = 3.5;
  const std::string text = StereoSettingsJson(options);
  const StereoOptions back = StereoOptionsFromJson(text, "x.json");
  EXPECT_EQ(StereoSettingsJson(back), text);
  EXPECT_EQ(DifferingStereoSettings(back, options), "");
  EXPECT_EQ(back.disparity.sgbm.p1, 300);
  EXPECT_EQ(back.disparity.sgbm.p2, std::nullopt);

  const StereoOptions from_empty = StereoOptionsFromJson("{}", "old.json");
  EXPECT_EQ(StereoSettingsJson(from_empty), StereoSettingsJson(StereoOptions{}));
  EXPECT_NE(DifferingStereoSettings(from_empty, options)
                .find("disparity.method: \"bm\" "
                      "(requested: \"sgbm\")"),
            std::string::npos);
  EXPECT_NE(DifferingStereoSettings(from_empty, options)
                .find("disparity.uniqueness_ratio: 15 "
                      "(requested: 7)"),
            std::string::npos);
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"sgbm_mode": "fast"}})", "m.json"),
               ParseError);
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"uniqueness_ratio": "x"}})", "m.json"),
               ParseError);
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"uniqueness_ratio": 500}})", "m.json"),
               std::invalid_argument);
  EXPECT_THROW(StereoOptionsFromJson("{", "m.json"), ParseError);
}

}  // namespace
}  // namespace stereodet
