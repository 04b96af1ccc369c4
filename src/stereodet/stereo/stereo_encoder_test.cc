#include "stereodet/stereo/stereo_encoder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "stereodet/stereo/dataset_encoder.h"
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

// Matching at half the size on a KITTI-sized road-and-wall scene: the full-resolution outputs keep
// their size and agree with the full-scale ones within the stated tolerances; the match-scale
// outputs (full_resolution false) are those before the upsampling.
TEST(StereoEncoderTest, HalfScaleAgreesWithFullScaleOnAPlanarScene) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.ground_pitch_deg = 1.0;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  const StereoOutputs all{.rgbh = true, .depth = true, .points = true};
  StereoOptions full_options;
  const StereoEncoding full =
      StereoEncoder(full_options).Encode(scene.left_bgr, scene.right_bgr, geometry, all);
  StereoOptions half_options;
  half_options.disparity.match_scale = 0.5;
  StageTimes times;
  StereoEncoder half_encoder(half_options);
  const StereoEncoding half =
      half_encoder.Encode(scene.left_bgr, scene.right_bgr, geometry, all, &times);
  ASSERT_TRUE(full.ground.fitted) << full.ground.reason;
  ASSERT_TRUE(half.ground.fitted) << half.ground.reason;
  EXPECT_EQ(times.Snapshot().count("upsample"), 1u);

  // Sizes: the documented full-resolution ones.
  for (const cv::Mat* image :
       {&half.disparity_px, &half.height_code, &half.depth_code, &half.rgbh, &half.network_image}) {
    EXPECT_EQ(image->size(), scene.left_bgr.size());
  }
  // The ground fit: the same plane within 2 cm of camera height and 0.2 degrees of tilt.
  EXPECT_NEAR(half.ground.camera_height_m, full.ground.camera_height_m, 0.02);
  EXPECT_NEAR(half.ground.tilt_deg, full.ground.tilt_deg, 0.2);

  // Where both have a disparity: |half - full| <= 1 px (full-size px) at 95% of the pixels (98.5%
  // measured), the depth within 5% at 90% (92%: 1 px is 8% at the 30 m wall), the height above
  // the ground within 0.1 m at 95% (98.6%); half scale finds at least 65% as many pixels (71%
  // measured: its 5 x 5 block fails the texture and uniqueness tests more often).
  long both = 0, full_valid = 0, half_valid = 0, disparity_close = 0, depth_close = 0,
       height_close = 0;
  for (int v = 0; v < full.disparity_px.rows; ++v) {
    for (int u = 0; u < full.disparity_px.cols; ++u) {
      const float df = full.disparity_px.at<float>(v, u), dh = half.disparity_px.at<float>(v, u);
      full_valid += IsValidDisparity(df);
      half_valid += IsValidDisparity(dh);
      // Codes are 0 exactly where there is no disparity, at either scale.
      ASSERT_EQ(half.height_code.at<uint16_t>(v, u) == 0, !IsValidDisparity(dh)) << v << "," << u;
      if (!IsValidDisparity(df) || !IsValidDisparity(dh)) continue;
      ++both;
      disparity_close += std::abs(dh - df) <= 1.0f;
      const double zf = geometry.DepthFromDisparity(df), zh = geometry.DepthFromDisparity(dh);
      depth_close += std::abs(zh - zf) <= 0.05 * zf;
      const double hf = full_options.height.Dequantize(full.height_code.at<uint16_t>(v, u));
      const double hh = half_options.height.Dequantize(half.height_code.at<uint16_t>(v, u));
      height_close += std::abs(hh - hf) <= 0.1;
    }
  }
  ASSERT_GT(both, 100000);
  EXPECT_GE(half_valid, 0.65 * full_valid);
  EXPECT_GE(disparity_close, 0.95 * both);
  EXPECT_GE(depth_close, 0.90 * both);
  EXPECT_GE(height_close, 0.95 * both);
  // RGB-H packs the full-size left image with the upsampled codes.
  const UnpackedRgbh unpacked = UnpackRgbh(half.rgbh);
  EXPECT_EQ(cv::norm(unpacked.height_code, half.height_code, cv::NORM_INF), 0.0);
  // The point cloud has a point per match-scale pixel at most: about a quarter as many.
  EXPECT_GT(half.points.size(), 0.15 * full.points.size());
  EXPECT_LT(half.points.size(), 0.35 * full.points.size());

  // At the match size: 621 x 188, the same codes before the upsampling, disparity in half-size px.
  StereoOutputs small_outputs{.rgbh = false, .depth = true};
  small_outputs.full_resolution = false;
  const StereoEncoding small =
      half_encoder.Encode(scene.left_bgr, scene.right_bgr, geometry, small_outputs);
  EXPECT_EQ(small.network_image.size(), scene.left_bgr.size());
  for (const cv::Mat* image : {&small.disparity_px, &small.height_code, &small.depth_code}) {
    EXPECT_EQ(image->size(), cv::Size(621, 188));
  }
  cv::Mat up_codes;
  cv::resize(small.height_code, up_codes, scene.left_bgr.size(), 0, 0, cv::INTER_NEAREST_EXACT);
  EXPECT_EQ(cv::norm(up_codes, half.height_code, cv::NORM_INF), 0.0);
  // ... and the full-resolution codes (what a `stereo` folder holds) give them back exactly.
  EXPECT_EQ(cv::norm(HeightCodesAtMatchSize(half.height_code, cv::Size(621, 188)),
                     small.height_code, cv::NORM_INF),
            0.0);
  EXPECT_EQ(cv::norm(UpsampleDisparity(small.disparity_px, scene.left_bgr.size()),
                     half.disparity_px, cv::NORM_INF),
            0.0);
  // An RGB-H image at the match size is refused (it packs the full-size network image).
  StereoOutputs bad = small_outputs;
  bad.rgbh = true;
  EXPECT_THROW(half_encoder.Encode(scene.left_bgr, scene.right_bgr, geometry, bad),
               std::invalid_argument);
}

// The wall of a planar scene at a known depth (30 m): matched at half the size, its median depth
// is within 2% of the truth, as at full size.
TEST(StereoEncoderTest, HalfScaleDepthOfAWallAtAKnownDepth) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.wall_depth_m = 30.0;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  for (double scale : {1.0, 0.5}) {
    StereoOptions options;
    options.disparity.match_scale = scale;
    const StereoEncoding encoding =
        StereoEncoder(options).Encode(scene.left_bgr, scene.right_bgr, geometry);
    std::vector<double> depths;
    // The wall's pixels: where the true disparity is the wall's (f b / 30).
    const float wall = static_cast<float>(geometry.DisparityFromDepth(30.0));
    for (int v = 0; v < scene.disparity_px.rows; ++v) {
      for (int u = 200; u < scene.disparity_px.cols; ++u) {
        if (std::abs(scene.disparity_px.at<float>(v, u) - wall) > 0.01f) continue;
        const float d = encoding.disparity_px.at<float>(v, u);
        if (IsValidDisparity(d)) depths.push_back(geometry.DepthFromDisparity(d));
      }
    }
    ASSERT_GT(depths.size(), 10000u) << scale;
    std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
    EXPECT_NEAR(depths[depths.size() / 2], 30.0, 0.6) << "match_scale " << scale;
  }
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

// match_scale travels in the "disparity" object; a record without it (every stereo.json and
// model.json written before it existed, the committed models' among them) reads as 1.
TEST(StereoSettingsJsonTest, MatchScaleRoundTripsAndReadsAsOneWhenAbsent) {
  StereoOptions half;
  half.disparity.match_scale = 0.5;
  const std::string text = StereoSettingsJson(half);
  EXPECT_NE(text.find("\"match_scale\": 0.5"), std::string::npos) << text;
  EXPECT_EQ(StereoOptionsFromJson(text, "s.json").disparity.match_scale, 0.5);
  EXPECT_EQ(DifferingStereoSettings(StereoOptions(), half),
            "disparity.match_scale: 1.0 (requested: 0.5)");
  // The full record of today's defaults without the key: an old file.
  nlohmann::json old = nlohmann::json::parse(StereoSettingsJson(StereoOptions()));
  old["disparity"].erase("match_scale");
  ASSERT_FALSE(old["disparity"].contains("match_scale"));
  EXPECT_EQ(StereoOptionsFromJson(old.dump(), "old.json").disparity.match_scale, 1.0);
  EXPECT_EQ(DifferingStereoSettings(StereoOptionsFromJson(old.dump(), "old.json"), StereoOptions()),
            "");
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"match_scale": 0}})", "m.json"),
               std::invalid_argument);
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"match_scale": 1.5}})", "m.json"),
               std::invalid_argument);
  EXPECT_THROW(StereoOptionsFromJson(R"({"disparity": {"match_scale": "half"}})", "m.json"),
               ParseError);
}

}  // namespace
}  // namespace stereodet
