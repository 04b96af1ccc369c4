// Stereo ("pseudo-LiDAR") point clouds: the points of valid disparity pixels in the velodyne frame,
// written as KITTI velodyne .bin files so that any LiDAR detector reads them unchanged.
#ifndef STEREODET_STEREO_POINT_CLOUD_H_
#define STEREODET_STEREO_POINT_CLOUD_H_

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/reprojection.h"

namespace stereodet {

struct PointCloudOptions {
  // Truncation. Depth is along the camera axis (f b / d), the quantity stereo measures; points
  // beyond are dropped. (Stereo depth error grows as z^2 / (f b): on KITTI, 16 m per pixel at 80
  // m.)
  double max_depth_m = 80.0;
  // Height above the ground plane (fitted or nominal). Below min_height_m is noise under the road;
  // above max_height_m is sky, trees and buildings, which no KITTI class reaches (vans ~2.5 m).
  double min_height_m = -1.0;
  double max_height_m = 3.0;
  // LiDAR-like subsampling; beams = 0 keeps every point. With beams > 0, points are grouped by
  // their elevation angle in the velo frame into `beams` rows evenly spaced over
  // [min_elevation_deg, max_elevation_deg] (an HDL-64E: 64 over -24.9..2.0 deg), and in each row
  // into azimuth bins of azimuth_step_deg (HDL-64E at 10 Hz: ~0.18 deg); each bin keeps the one
  // point nearest its beam's elevation. Points outside the elevation span are dropped.
  int beams = 0;
  double min_elevation_deg = -24.9;
  double max_elevation_deg = 2.0;
  double azimuth_step_deg = 0.18;
  void Check() const;  // throws std::invalid_argument
};

// Reflectance of a stereo point: the left image's grey level scaled to [0, 1].
inline float ReflectanceFromGrey(uint8_t grey) { return grey * (1.0f / 255.0f); }

// Points in the velo frame in row-major pixel order, reflectance = left grey level / 255.
// Requires: disparity CV_32FC1 and left grey CV_8UC1 of the same size.
std::vector<VeloPoint> StereoPointCloud(const cv::Mat& disparity_px, const cv::Mat& left_grey,
                                        const StereoGeometry& geometry, const GroundPlane& ground,
                                        const PointCloudOptions& options = {});

// The LiDAR-like subsampling described in PointCloudOptions (identity when options.beams == 0).
// Output keeps the input order of the surviving points.
std::vector<VeloPoint> SubsampleToBeams(const std::vector<VeloPoint>& points,
                                        const PointCloudOptions& options);

}  // namespace stereodet

#endif  // STEREODET_STEREO_POINT_CLOUD_H_
