#include "stereodet/stereo/point_cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

class PointCloudTest : public ::testing::Test {
 protected:
  StereoGeometry geometry_ = StereoGeometry::FromCalibration(KittiLikeCalibration());
  GroundPlane ground_ = GroundPlane::Nominal(1.65);
};

TEST_F(PointCloudTest, PointsAreReprojectedPixelsInTheVeloFrame) {
  // A 4x3 patch around the principal point at 10 m, one invalid pixel.
  const int u0 = 600, v0 = 170;
  cv::Mat disparity(375, 1242, CV_32FC1, cv::Scalar(kInvalidDisparity));
  cv::Mat grey(375, 1242, CV_8UC1, cv::Scalar(0));
  for (int v = v0; v < v0 + 3; ++v) {
    for (int u = u0; u < u0 + 4; ++u) {
      disparity.at<float>(v, u) = static_cast<float>(geometry_.DisparityFromDepth(10.0));
      grey.at<uint8_t>(v, u) = static_cast<uint8_t>(u - u0 + 10 * (v - v0));
    }
  }
  disparity.at<float>(v0, u0) = kInvalidDisparity;
  const std::vector<VeloPoint> points = StereoPointCloud(disparity, grey, geometry_, ground_);
  ASSERT_EQ(points.size(), 11u);
  // Row-major order: the first point is pixel (u0 + 1, v0).
  const Eigen::Vector3d expected =
      geometry_.velo_from_rect * geometry_.PointInRect(u0 + 1, v0, disparity.at<float>(v0, u0 + 1));
  EXPECT_NEAR(points[0].x, expected.x(), 1e-5);
  EXPECT_NEAR(points[0].y, expected.y(), 1e-5);
  EXPECT_NEAR(points[0].z, expected.z(), 1e-5);
  EXPECT_FLOAT_EQ(points[0].reflectance, 1.0f / 255);
  EXPECT_FLOAT_EQ(points.back().reflectance, 23.0f / 255);
  // 10 m ahead of the camera is ~10.3 m ahead of the LiDAR (velo x forward, z up).
  EXPECT_NEAR(points[0].x, 10.27, 0.05);
  EXPECT_NEAR(points[0].z, 0.0, 0.15);
}

TEST_F(PointCloudTest, TruncatesByDepthAndHeight) {
  cv::Mat disparity(375, 1242, CV_32FC1, cv::Scalar(kInvalidDisparity));
  const cv::Mat grey(375, 1242, CV_8UC1, cv::Scalar(100));
  const int u = 700;
  // Rows 180 and 181 are 0.9 and 0.8 m below the camera at these depths, 0.8 m above the ground.
  disparity.at<float>(180, u) = static_cast<float>(geometry_.DisparityFromDepth(90.0));  // too far
  disparity.at<float>(181, u) = static_cast<float>(geometry_.DisparityFromDepth(70.0));  // kept
  // 5 m ahead, row 0: 5 * (0 - 172.85) / 721.5 = 1.2 m above the camera, 2.85 m up: kept; row
  // 374 at 2 m: ~0.56 m below the camera, 1.09 m up: kept; a point 2 m down at 3 m depth: dropped.
  disparity.at<float>(0, u) = static_cast<float>(geometry_.DisparityFromDepth(5.0));
  disparity.at<float>(374, u) = static_cast<float>(geometry_.DisparityFromDepth(2.0));
  PointCloudOptions options;
  EXPECT_EQ(StereoPointCloud(disparity, grey, geometry_, ground_, options).size(), 3u);
  options.max_height_m = 2.0;  // drops the 2.85 m one
  EXPECT_EQ(StereoPointCloud(disparity, grey, geometry_, ground_, options).size(), 2u);
  options.max_depth_m = 100;
  EXPECT_EQ(StereoPointCloud(disparity, grey, geometry_, ground_, options).size(), 3u);
  GroundPlane high_ground = GroundPlane::Nominal(3.0);  // every point is >= 2 m above it
  options.max_height_m = 1.2;
  EXPECT_EQ(StereoPointCloud(disparity, grey, geometry_, high_ground, options).size(), 0u);
  options.min_height_m = options.max_height_m;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

TEST(PointCloudOptionsTest, MaxDepthMustBeFiniteAndPositive) {
  PointCloudOptions options;
  for (double depth : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    options.max_depth_m = depth;
    EXPECT_THROW(options.Check(), std::invalid_argument) << depth;
  }
  options.max_depth_m = 0.5;
  EXPECT_NO_THROW(options.Check());
}

TEST_F(PointCloudTest, RoundTripsThroughVelodyneBin) {
  cv::Mat disparity(375, 1242, CV_32FC1);
  cv::RNG rng(4);
  rng.fill(disparity, cv::RNG::UNIFORM, -5.0, 60.0);
  cv::Mat grey(375, 1242, CV_8UC1);
  rng.fill(grey, cv::RNG::UNIFORM, 0, 256);
  const std::vector<VeloPoint> points = StereoPointCloud(disparity, grey, geometry_, ground_);
  ASSERT_GT(points.size(), 1000u);
  const TestTempDir temp;
  const fs::path path = temp / "000001.bin";
  WriteVelodyne(path, points);
  EXPECT_EQ(fs::file_size(path), points.size() * 16);
  EXPECT_EQ(ReadVelodyne(path), points);
}

TEST(SubsampleToBeamsTest, KeepsOnePointPerBeamAndAzimuthBin) {
  PointCloudOptions options;
  options.beams = 3;
  options.min_elevation_deg = -2.0;
  options.max_elevation_deg = 0.0;  // beams at -2, -1, 0 deg
  options.azimuth_step_deg = 1.0;
  auto at = [](double elevation_deg, double azimuth_deg, float tag) {
    const double r = 10, e = elevation_deg * M_PI / 180, a = azimuth_deg * M_PI / 180;
    return VeloPoint{static_cast<float>(r * std::cos(e) * std::cos(a)),
                     static_cast<float>(r * std::cos(e) * std::sin(a)),
                     static_cast<float>(r * std::sin(e)), tag};
  };
  const std::vector<VeloPoint> points = {
      at(-1.2, 0.5, 1),   // beam -1, bin 0: farther from the beam than the next one
      at(-0.95, 0.6, 2),  // beam -1, bin 0: kept
      at(-1.0, 1.5, 3),   // beam -1, bin 1: kept
      at(0.1, 0.5, 4),    // beam 0: kept
      at(-3.0, 0.5, 5),   // below the lowest beam: dropped
      at(5.0, 0.5, 6),    // above: dropped
  };
  const std::vector<VeloPoint> kept = SubsampleToBeams(points, options);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0].reflectance, 2);
  EXPECT_EQ(kept[1].reflectance, 3);
  EXPECT_EQ(kept[2].reflectance, 4);
  options.beams = 0;
  EXPECT_EQ(SubsampleToBeams(points, options).size(), points.size());
}

}  // namespace
}  // namespace stereodet
