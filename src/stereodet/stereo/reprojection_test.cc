#include "stereodet/stereo/reprojection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/planar_scene.h"

namespace stereodet {
namespace {

TEST(StereoGeometryTest, TakesFocalBaselineAndCameraOffsetFromCalibration) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  EXPECT_DOUBLE_EQ(geometry.focal_px, 7.215377e+02);
  EXPECT_DOUBLE_EQ(geometry.baseline_m, calib.BaselineM());
  // (P2(0,3) - P3(0,3) - cx (P2(2,3) - P3(2,3))) / f, with KITTI's small z offsets.
  EXPECT_NEAR(geometry.baseline_m, 0.532712, 1e-6);
  EXPECT_NEAR(geometry.camera2_in_rect.x(), -0.0599, 1e-3);  // camera 2 is ~6 cm left of cam 0
  EXPECT_DOUBLE_EQ(geometry.cx_px, 6.095593e+02);
  EXPECT_DOUBLE_EQ(geometry.DepthFromDisparity(geometry.DisparityFromDepth(12.5)), 12.5);
}

TEST(StereoGeometryTest, RejectsCalibrationWithoutBaseline) {
  Calibration calib = KittiLikeCalibration();
  calib.projection[3] = calib.projection[2];
  EXPECT_THROW(StereoGeometry::FromCalibration(calib), std::invalid_argument);
}

// Property: a rect point projected into both cameras and reprojected through its disparity comes
// back.
TEST(StereoGeometryTest, ProjectThenReprojectThroughDisparityRoundTrips) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-15, 15), y(-3, 2), z(2, 80);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d point(x(rng), y(rng), z(rng));
    const Eigen::Vector2d left = calib.ProjectRectToImage(point, 2);
    const Eigen::Vector2d right = calib.ProjectRectToImage(point, 3);
    const double disparity = left.x() - right.x();
    ASSERT_GT(disparity, 0);
    const Eigen::Vector3d back = geometry.PointInRect(left.x(), left.y(), disparity);
    // KITTI's cameras 2 and 3 differ by dz ~ 16 um along z, which z = f b / d ignores: the depth is
    // then off by |x - c3.x| dz / b and the point by that times the ray's length.
    const Eigen::Vector3d c2 = calib.CameraCentreInRect(2), c3 = calib.CameraCentreInRect(3);
    const Eigen::Vector3d ray = (point - c2) / (point.z() - c2.z());
    const double bound = 1e-9 + 1.5 * std::abs(point.x() - c3.x()) * std::abs(c3.z() - c2.z()) /
                                    geometry.baseline_m * ray.norm();
    EXPECT_LT((back - point).norm(), bound) << point.transpose();
    EXPECT_LT(bound, 0.01);
    // And it agrees with the calibration's own unprojection at the same depth.
    const double depth = geometry.DepthFromDisparity(disparity);
    EXPECT_LT((calib.UnprojectImageToRect(left, depth, 2) - back).norm(), 1e-9);
  }
}

// Scaled(): by hand on KITTI's numbers, and a pixel of the full image mapped to the resized one
// (centres: u' = (u + 0.5) s - 0.5, disparity d' = d s_x) reprojects to the same point.
TEST(StereoGeometryTest, ScaledGeometryReprojectsResizedPixelsToTheSamePoints) {
  const StereoGeometry geometry = StereoGeometry::FromCalibration(KittiLikeCalibration());
  const double sx = 621.0 / 1242.0, sy = 188.0 / 375.0;
  const StereoGeometry scaled = geometry.Scaled(sx, sy);
  EXPECT_DOUBLE_EQ(scaled.focal_px, geometry.focal_px * 0.5);
  EXPECT_DOUBLE_EQ(scaled.FocalY(), geometry.focal_px * sy);
  EXPECT_DOUBLE_EQ(scaled.cx_px, (geometry.cx_px + 0.5) * 0.5 - 0.5);
  EXPECT_DOUBLE_EQ(scaled.cy_px, (geometry.cy_px + 0.5) * sy - 0.5);
  EXPECT_EQ(scaled.baseline_m, geometry.baseline_m);
  EXPECT_EQ(geometry.FocalY(), geometry.focal_px);  // square pixels unless scaled
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0, 1242), v(0, 375), d(1, 128);
  for (int i = 0; i < 200; ++i) {
    const double uu = u(rng), vv = v(rng), dd = d(rng);
    const Eigen::Vector3d full = geometry.PointInRect(uu, vv, dd);
    const Eigen::Vector3d small =
        scaled.PointInRect((uu + 0.5) * sx - 0.5, (vv + 0.5) * sy - 0.5, dd * sx);
    EXPECT_LT((small - full).norm(), 1e-9 * full.norm()) << uu << "," << vv << "," << dd;
  }
  EXPECT_THROW(geometry.Scaled(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(geometry.Scaled(0.5, std::nan("")), std::invalid_argument);
}

TEST(ReprojectionTest, FrontoParallelPlaneGivesItsDepthAndHeight) {
  const StereoGeometry geometry = StereoGeometry::FromCalibration(KittiLikeCalibration());
  const double depth_m = 12.5;
  cv::Mat disparity(40, 60, CV_32FC1, cv::Scalar(geometry.DisparityFromDepth(depth_m)));
  disparity.at<float>(0, 0) = kInvalidDisparity;
  const cv::Mat depth = DepthFromDisparity(disparity, geometry);
  const cv::Mat points = PointsInRectFromDisparity(disparity, geometry);
  const GroundPlane ground = GroundPlane::Nominal(1.65);
  const cv::Mat height = HeightFromDisparity(disparity, geometry, ground);
  EXPECT_TRUE(std::isnan(depth.at<float>(0, 0)));
  EXPECT_TRUE(std::isnan(height.at<float>(0, 0)));
  EXPECT_TRUE(std::isnan(points.at<cv::Vec3f>(0, 0)[2]));
  for (int v = 1; v < 40; v += 7) {
    for (int u = 1; u < 60; u += 11) {
      EXPECT_NEAR(depth.at<float>(v, u), depth_m, 1e-5);
      const cv::Vec3f p = points.at<cv::Vec3f>(v, u);
      // Depth is in front of camera 2, which sits at c2.z in rect.
      EXPECT_NEAR(p[2], depth_m + geometry.camera2_in_rect.z(), 1e-5);
      // Height above the nominal ground: 1.65 m minus rect y, y = c2.y + z (v - cy) / f.
      const double y =
          geometry.camera2_in_rect.y() + depth_m * (v - geometry.cy_px) / geometry.focal_px;
      EXPECT_NEAR(p[1], y, 1e-5);
      EXPECT_NEAR(height.at<float>(v, u), 1.65 - y, 1e-5);
    }
  }
}

// End to end through the matcher: a textured wall 15 m ahead filling the view.
TEST(ReprojectionTest, MatchedWallGivesItsDepthWithinSubPixelPrecision) {
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.height_px = 100;
  scene_options.camera_height_m = 100;  // ground out of view
  scene_options.wall_depth_m = 15;
  scene_options.texture_scale_m = 0.02;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);
  DisparityOptions options;
  options.num_disparities = 48;
  DisparityMatcher matcher(options);
  const cv::Mat disparity = matcher.Compute(scene.left_bgr, scene.right_bgr);
  const cv::Mat depth = DepthFromDisparity(disparity, geometry);
  // The wall is at rect z = 15, i.e. 15 - c2.z in front of camera 2.
  const double truth = 15 - geometry.camera2_in_rect.z();
  // 0.5 px of disparity at this depth:
  const double tolerance = 0.5 * truth * truth / (geometry.focal_px * geometry.baseline_m);
  long valid = 0, close = 0;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 64; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (std::isnan(z)) continue;
      ++valid;
      close += std::abs(z - truth) < tolerance;
    }
  }
  EXPECT_GT(valid, 0.8 * depth.rows * (depth.cols - 64));
  EXPECT_GT(close, 0.98 * valid) << close << " / " << valid;
  // The ground fit sees a wall, not a road: it must fall back to the nominal plane and say so.
  const GroundPlaneFit fit = FitGroundPlane(disparity, geometry);
  EXPECT_FALSE(fit.fitted);
  EXPECT_DOUBLE_EQ(fit.plane.offset_m, 1.65);
  EXPECT_FALSE(fit.reason.empty());
}

struct GroundCase {
  double pitch_deg, roll_deg, camera_height_m;
};

class GroundFitTest : public ::testing::TestWithParam<GroundCase> {};

TEST_P(GroundFitTest, RecoversPitchedAndRolledRoad) {
  const GroundCase c = GetParam();
  const Calibration calib = KittiLikeCalibration();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarSceneOptions scene_options;
  scene_options.ground_pitch_deg = c.pitch_deg;
  scene_options.ground_roll_deg = c.roll_deg;
  scene_options.camera_height_m = c.camera_height_m;
  const PlanarScene scene = RenderPlanarScene(calib, scene_options);

  // From the exact disparity: the plane itself.
  const GroundPlaneFit exact = FitGroundPlane(scene.disparity_px, geometry);
  ASSERT_TRUE(exact.fitted) << exact.reason;
  EXPECT_NEAR(exact.plane.offset_m, c.camera_height_m, 1e-3);
  EXPECT_GT(exact.plane.normal_in_rect.dot(scene.ground.normal_in_rect),
            std::cos(0.05 * M_PI / 180));

  // From block matching: within a few centimetres and a few tenths of a degree.
  DisparityMatcher matcher;
  const cv::Mat disparity = matcher.Compute(scene.left_bgr, scene.right_bgr);
  const GroundPlaneFit fit = FitGroundPlane(disparity, geometry);
  ASSERT_TRUE(fit.fitted) << fit.reason;
  EXPECT_EQ(fit.reason, "fitted");
  EXPECT_GT(fit.inliers, 200);
  EXPECT_NEAR(fit.plane.offset_m, c.camera_height_m, 0.03);
  EXPECT_GT(fit.plane.normal_in_rect.dot(scene.ground.normal_in_rect), std::cos(0.3 * M_PI / 180));

  // Heights of ground pixels are ~0 with the fitted plane.
  const cv::Mat height = HeightFromDisparity(disparity, geometry, fit.plane);
  const int v = scene.disparity_px.rows - 20, u = 700;
  ASSERT_FALSE(std::isnan(height.at<float>(v, u)));
  EXPECT_NEAR(height.at<float>(v, u), 0.0, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Roads, GroundFitTest,
                         ::testing::Values(GroundCase{0, 0, 1.65}, GroundCase{2.0, 0, 1.65},
                                           GroundCase{-1.5, 1.5, 1.65}, GroundCase{0, 0, 1.9}));

// A road tilted 3 degrees, beyond the 1.5 degree tolerance: the fit is accepted but suspect, and
// with suspect_uses_prior the nominal plane (the prior) replaces it. A 1 degree tilt is within it.
TEST(GroundFitTest, FlagsAFitBeyondTheToleranceAndUsesThePriorWhenAsked) {
  const StereoGeometry geometry = StereoGeometry::FromCalibration(KittiLikeCalibration());
  auto scene_with = [](double pitch_deg, double camera_height_m) {
    PlanarSceneOptions scene_options;
    scene_options.ground_pitch_deg = pitch_deg;
    scene_options.camera_height_m = camera_height_m;
    return RenderPlanarScene(KittiLikeCalibration(), scene_options).disparity_px;
  };
  const cv::Mat tilted = scene_with(3.0, 1.65);
  GroundPlaneOptions options;
  const GroundPlaneFit kept = FitGroundPlane(tilted, geometry, options);
  EXPECT_TRUE(kept.fitted);
  EXPECT_TRUE(kept.suspect);
  EXPECT_NEAR(kept.tilt_deg, 3.0, 0.05);
  EXPECT_GT(kept.InlierFraction(), 0.9);
  EXPECT_DOUBLE_EQ(kept.InlierFraction(), static_cast<double>(kept.inliers) / kept.samples);

  options.suspect_uses_prior = true;
  const GroundPlaneFit prior = FitGroundPlane(tilted, geometry, options);
  EXPECT_FALSE(prior.fitted);
  EXPECT_TRUE(prior.suspect);
  EXPECT_EQ(prior.plane.normal_in_rect, Eigen::Vector3d(0, -1, 0));
  EXPECT_DOUBLE_EQ(prior.plane.offset_m, 1.65);
  EXPECT_EQ(prior.reason.rfind("suspect fit (tilt 3.0", 0), 0u) << prior.reason;

  const GroundPlaneFit level = FitGroundPlane(scene_with(1.0, 1.65), geometry, options);
  EXPECT_TRUE(level.fitted);
  EXPECT_FALSE(level.suspect);
  // A camera 0.35 m above its nominal height is suspect as well (tolerance 0.25 m).
  const GroundPlaneFit high = FitGroundPlane(scene_with(0.0, 2.0), geometry, options);
  EXPECT_TRUE(high.suspect);
  EXPECT_FALSE(high.fitted);
  options.warn_camera_height_m = 0.4;
  EXPECT_TRUE(FitGroundPlane(scene_with(0.0, 2.0), geometry, options).fitted);
  options.warn_tilt_deg = -1;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(GroundFitTest, FallsBackWithoutStereo) {
  const StereoGeometry geometry = StereoGeometry::FromCalibration(KittiLikeCalibration());
  const cv::Mat nothing(375, 1242, CV_32FC1, cv::Scalar(kInvalidDisparity));
  GroundPlaneOptions options;
  options.nominal_camera_height_m = 1.7;
  const GroundPlaneFit fit = FitGroundPlane(nothing, geometry, options);
  EXPECT_FALSE(fit.fitted);
  EXPECT_EQ(fit.samples, 0);
  EXPECT_NE(fit.reason.find("too few"), std::string::npos) << fit.reason;
  EXPECT_DOUBLE_EQ(fit.plane.offset_m, 1.7);
  EXPECT_EQ(fit.plane.normal_in_rect, Eigen::Vector3d(0, -1, 0));
  options.enabled = false;
  EXPECT_FALSE(FitGroundPlane(nothing, geometry, options).fitted);
  options.roi_fraction = 0;
  EXPECT_THROW(FitGroundPlane(nothing, geometry, options), std::invalid_argument);
}

TEST(QuantizationTest, HeightCodesAreNineBitsWithZeroReserved) {
  const HeightQuantization q;  // [-1, 4] m
  EXPECT_EQ(q.Quantize(std::nan("")), 0);
  EXPECT_EQ(q.Quantize(-1.0), 1);
  EXPECT_EQ(q.Quantize(-7.0), 1);
  EXPECT_EQ(q.Quantize(4.0), 511);
  EXPECT_EQ(q.Quantize(40.0), 511);
  EXPECT_EQ(q.Quantize(1.5), 256);  // 1 + 2.5 / 5 * 510
  EXPECT_TRUE(std::isnan(q.Dequantize(0)));
  EXPECT_DOUBLE_EQ(q.Dequantize(1), -1.0);
  EXPECT_DOUBLE_EQ(q.Dequantize(511), 4.0);
  const double step = 5.0 / 510;
  for (double h = -1.0; h <= 4.0; h += 0.0123) {
    EXPECT_LE(std::abs(q.Dequantize(q.Quantize(h)) - h), step / 2 + 1e-12) << h;
  }
  HeightQuantization bad;
  bad.max_m = bad.min_m;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

TEST(QuantizationTest, DepthCodes) {
  DepthQuantization q;  // [0, 80] m, 16 bits
  EXPECT_EQ(q.MaxCode(), 65535);
  EXPECT_EQ(q.Quantize(std::nan("")), 0);
  EXPECT_EQ(q.Quantize(0.0), 1);
  EXPECT_EQ(q.Quantize(80.0), 65535);
  EXPECT_EQ(q.Quantize(500.0), 65535);
  const double step = 80.0 / 65534;
  EXPECT_NEAR(q.Dequantize(q.Quantize(33.3)), 33.3, step / 2 + 1e-12);
  q.bits = 8;
  EXPECT_EQ(q.Quantize(80.0), 255);
  EXPECT_EQ(q.Quantize(40.0), 128);  // 1 + round(0.5 * 254)
  q.bits = 17;
  EXPECT_THROW(q.Check(), std::invalid_argument);
}

TEST(QuantizationTest, ImagesKeepReservedZero) {
  cv::Mat height = (cv::Mat_<float>(1, 3) << NAN, 0.0f, 4.0f);
  const cv::Mat codes = QuantizeHeight(height, {});
  ASSERT_EQ(codes.type(), CV_16UC1);
  EXPECT_EQ(codes.at<uint16_t>(0, 0), 0);
  EXPECT_EQ(codes.at<uint16_t>(0, 1), 103);  // 1 + round(1 / 5 * 510)
  EXPECT_EQ(codes.at<uint16_t>(0, 2), 511);
  const cv::Mat depth_codes = QuantizeDepth(height, {});
  EXPECT_EQ(depth_codes.at<uint16_t>(0, 0), 0);
  EXPECT_EQ(depth_codes.at<uint16_t>(0, 1), 1);
}

}  // namespace
}  // namespace stereodet
