#include "stereodet/geometry/calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace stereodet {
namespace {

TEST(CalibrationTest, DerivedStereoQuantitiesOfKitti) {
  const Calibration calib = KittiLikeCalibration();
  EXPECT_DOUBLE_EQ(calib.FocalPx(), 721.5377);
  EXPECT_DOUBLE_EQ(calib.PrincipalPointPx().x(), 609.5593);
  EXPECT_DOUBLE_EQ(calib.PrincipalPointPx().y(), 172.854);
  // P = K [I | t] with t = K^-1 P.col(3); t_x = (P(0,3) - cx P(2,3)) / f. The P(2,3) term is small
  // but not negligible: dropping it would misplace camera 2 by 2.3 mm.
  const double t2x = (44.85728 - 609.5593 * 2.745884e-03) / 721.5377;
  const double t3x = (-339.5242 - 609.5593 * 2.729905e-03) / 721.5377;
  EXPECT_NEAR(calib.CameraCentreInRect(2).x(), -t2x, 1e-12);
  EXPECT_NEAR(calib.CameraCentreInRect(2).z(), -2.745884e-03, 1e-12);
  EXPECT_NEAR(calib.CameraCentreInRect(3).x(), -t3x, 1e-12);
  EXPECT_NEAR(calib.BaselineM(), t2x - t3x, 1e-12);
  EXPECT_NEAR(calib.BaselineM(), 0.5327, 1e-4);
  EXPECT_NO_THROW(calib.CheckStereo());
  Calibration mono = calib;
  mono.projection[3] = mono.projection[2];
  EXPECT_THROW(mono.CheckStereo(), std::invalid_argument);
  EXPECT_THROW(calib.CameraCentreInRect(4), std::invalid_argument);
}

TEST(CalibrationTest, ProjectThenUnprojectIsIdentity) {
  const Calibration calib = KittiLikeCalibration();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> x(-20, 20), y(-2, 3), z(2, 80);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d point(x(rng), y(rng), z(rng));
    for (int camera : {2, 3}) {
      double depth = 0;
      const Eigen::Vector2d pixel = calib.ProjectRectToImage(point, camera, &depth);
      const Eigen::Vector3d back = calib.UnprojectImageToRect(pixel, depth, camera);
      ASSERT_LT((back - point).norm(), 1e-9) << i;
    }
  }
}

TEST(CalibrationTest, VeloRectRoundTripAndAxes) {
  const Calibration calib = KittiLikeCalibration();
  // A point 10 m ahead of the LiDAR is about 10 m ahead (z) of the camera and little to the side.
  const Eigen::Vector3d ahead = calib.RectFromVelo() * Eigen::Vector3d(10, 0, 0);
  EXPECT_NEAR(ahead.z(), 10 - 0.27, 0.1);
  EXPECT_NEAR(ahead.x(), 0.0, 0.1);
  // Up in the LiDAR frame is -y in the camera frame.
  const Eigen::Vector3d up = calib.RectFromVelo().linear() * Eigen::Vector3d(0, 0, 1);
  EXPECT_NEAR(up.y(), -1.0, 0.01);
  const Eigen::Vector3d p(3, -1, 25);
  EXPECT_LT((calib.RectFromVelo() * (calib.VeloFromRect() * p) - p).norm(), 1e-12);
}

TEST(CalibrationTest, AlphaMatchesKittiFrame000000) {
  // training/label_2/000000.txt: Pedestrian ... alpha -0.20 ... location 1.84 1.47 8.41, ry 0.01.
  const Eigen::Vector3d location(1.84, 1.47, 8.41);
  EXPECT_NEAR(AlphaFromRotationY(0.01, location), -0.20, 0.01);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), x(-30, 30), z(1, 80);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector3d loc(x(rng), 1.6, z(rng));
    const double ry = angle(rng);
    const double alpha = AlphaFromRotationY(ry, loc);
    ASSERT_GE(alpha, -M_PI);
    ASSERT_LT(alpha, M_PI);
    ASSERT_NEAR(WrapAngle(RotationYFromAlpha(alpha, loc) - ry), 0.0, 1e-12);
  }
}

TEST(CalibrationTest, WrapAngleAndDepthError) {
  EXPECT_DOUBLE_EQ(WrapAngle(0.5), 0.5);
  EXPECT_NEAR(WrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(-5 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(M_PI), -M_PI, 1e-12);
  // z = 20 m, b = 0.54 m, f = 720 px, 1 px of disparity error: 400 / 388.8 m.
  EXPECT_NEAR(StereoDepthError(20, 0.54, 720, 1.0), 400.0 / 388.8, 1e-12);
  EXPECT_THROW(StereoDepthError(20, 0, 720, 1), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
