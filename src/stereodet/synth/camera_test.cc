#include "stereodet/synth/camera.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stereodet/synth/lidar.h"
#include "stereodet/synth/test_scene.h"

namespace stereodet {
namespace {

using testing::AddBoxObject;
using testing::GroundOnlyScene;
using testing::MakeBox3D;

TEST(SynthCalibrationTest, FullResolutionIsKittiLike) {
  const Calibration full = SynthCalibration(1242, 375);
  const Calibration kitti = KittiLikeCalibration();
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(full.projection[i].isApprox(kitti.projection[i], 1e-12));
  EXPECT_NEAR(full.FocalPx(), 721.5377, 1e-9);
  EXPECT_NEAR(full.BaselineM(), kitti.BaselineM(), 1e-12);
  EXPECT_NEAR(full.CameraCentreInRect(2).x(), -0.06, 0.01);
  // The LiDAR 1.73 m above the road when the camera is 1.65 m above it.
  EXPECT_NEAR(1.65 - full.RectFromVelo().translation().y(), 1.73, 0.01);
}

TEST(SynthCalibrationTest, ScaledIntrinsicsKeepTheFieldOfView) {
  const Calibration small = SynthCalibration(621, 188);
  const Calibration full = SynthCalibration(1242, 375);
  EXPECT_NEAR(small.FocalPx(), full.FocalPx() / 2, 1e-9);
  EXPECT_NEAR(small.BaselineM(), full.BaselineM(), 1e-12);  // same rig
  // A far point near the image corner maps to the corresponding place in both.
  const Eigen::Vector3d point(-30.0, 1.0, 40.0);
  const Eigen::Vector2d a = full.ProjectRectToImage(point), b = small.ProjectRectToImage(point);
  EXPECT_NEAR((a.x() + 0.5) / 2 - 0.5, b.x(), 1e-6);
  EXPECT_THROW(SynthCalibration(4, 100), std::invalid_argument);
}

TEST(CameraTest, GroundTruthDisparityMatchesDepth) {
  const Calibration calib = SynthCalibration(320, 96);
  Scene scene = GroundOnlyScene();
  AddBoxObject(scene, "Car", MakeBox3D(2.0, 1.0, 3.0, 0.5, 1.65, 12.0, 0.4));
  scene.primitives.push_back(MakeBox(Eigen::Vector3f(0, 0, 40), Eigen::Vector3f(30, 10, 0.5f),
                                     Eigen::Matrix3f::Identity(), 1));
  scene.Finalize();
  RenderRequest left;
  left.width = 320;
  left.height = 96;
  left.points = true;
  RenderRequest right = left;
  right.camera = 3;
  right.points = false;
  const CameraRender l = RenderCamera(scene, calib, left), r = RenderCamera(scene, calib, right);
  const cv::Mat disparity = GroundTruthDisparity(calib, l, r);
  const double fb = calib.FocalPx() * calib.BaselineM();
  int valid = 0, occluded = 0;
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = 0; u < disparity.cols; ++u) {
      const float d = disparity.at<float>(v, u), z = l.depth.at<float>(v, u);
      if (z <= 0.0f) {
        EXPECT_EQ(d, 0.0f);  // sky: no ground truth
        continue;
      }
      if (d == 0.0f) {
        ++occluded;
        continue;
      }
      ++valid;
      EXPECT_NEAR(d, fb / z, 2e-3 * fb / z + 1e-3) << u << "," << v;
    }
  }
  EXPECT_GT(valid, 320 * 96 / 2);
  // The box hides some wall from the right camera, and the left image border strip is unseen.
  EXPECT_GT(occluded, 0);
  // KITTI's encoding round-trips to 1/256 px.
  const cv::Mat decoded = DecodeKittiDisparity(EncodeKittiDisparity(disparity));
  EXPECT_LE(cv::norm(decoded, disparity, cv::NORM_INF), 0.5 / 256 + 1e-6);
}

TEST(CameraTest, RenderIsDeterministicAndNoiseDependsOnSeed) {
  const Calibration calib = SynthCalibration(160, 48);
  Scene scene = GroundOnlyScene();
  scene.Finalize();
  RenderRequest request;
  request.width = 160;
  request.height = 48;
  request.noise_seed = 1;
  const cv::Mat a = RenderCamera(scene, calib, request).image;
  const cv::Mat b = RenderCamera(scene, calib, request).image;
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  request.noise_seed = 2;
  const cv::Mat c = RenderCamera(scene, calib, request).image;
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.type(), CV_8UC3);
}

TEST(LidarTest, ReturnsLieOnTheSurfaces) {
  const Calibration calib = SynthCalibration(1242, 375);
  Scene scene = GroundOnlyScene();
  const Box3D box = MakeBox3D(1.5, 1.8, 4.0, 1.0, 1.65, 10.0, 0.2);
  AddBoxObject(scene, "Car", box);
  scene.Finalize();
  LidarOptions options;
  options.azimuth_step_deg = 0.5;
  for (double noise : {0.0, 0.02}) {
    options.range_noise_m = noise;
    const std::vector<VeloPoint> scan = SimulateLidar(scene, calib, options, 7);
    ASSERT_GT(scan.size(), 1000u);
    const Eigen::Affine3d rect_from_velo = calib.RectFromVelo();
    int on_box = 0;
    for (const VeloPoint& p : scan) {
      const Eigen::Vector3d x = rect_from_velo * Eigen::Vector3d(p.x, p.y, p.z);
      const double tolerance = 1e-3 + 5.0 * noise;  // along the ray; the surfaces face the sensor
      const bool on_ground = std::abs(x.y() - 1.65) < tolerance * 3.0;
      const bool in_box =
          scene.primitives[0].Contains(x.cast<float>(), static_cast<float>(tolerance));
      EXPECT_TRUE(on_ground || in_box) << x.transpose();
      on_box += in_box && !on_ground;
      EXPECT_GE(p.reflectance, 0.0f);
      EXPECT_LE(p.reflectance, 1.0f);
      const double range = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
      EXPECT_LE(range, options.max_range_m + 0.2);
    }
    EXPECT_GT(on_box, 100);
  }
}

TEST(LidarTest, BeamLayoutIsHdl64) {
  const std::vector<double> e = Hdl64ElevationsDeg();
  ASSERT_EQ(e.size(), 64u);
  EXPECT_DOUBLE_EQ(e.front(), 2.0);
  EXPECT_DOUBLE_EQ(e.back(), -24.9);
  for (size_t i = 1; i < e.size(); ++i) EXPECT_LT(e[i], e[i - 1]);
}

}  // namespace
}  // namespace stereodet
