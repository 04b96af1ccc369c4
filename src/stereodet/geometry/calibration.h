// KITTI camera/LiDAR calibration and the projections between its frames.
//
// Frames (KITTI object benchmark):
//  - velo: the Velodyne HDL-64E, x forward, y left, z up, metres.
//  - cam0: the unrectified reference camera (camera 0, grey, left), x right, y down, z forward.
//  - rect: the rectified frame of camera 0. Labels (Box3D::location) live here; every P_i maps it
//  to
//    the image of camera i. Cameras 2 (left colour) and 3 (right colour) are the stereo pair.
//  - imu: the GPS/IMU unit.
// KITTI's file names (P0..P3, R0_rect, Tr_velo_to_cam, Tr_imu_to_velo) are kept to the parser; here
// they are `projection[i]`, `rect_from_cam0`, `cam0_from_velo`, `velo_from_imu`.
#ifndef STEREODET_GEOMETRY_CALIBRATION_H_
#define STEREODET_GEOMETRY_CALIBRATION_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

namespace stereodet {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

struct Calibration {
  // P_i: rect -> homogeneous pixels of camera i, i = 0..3 (KITTI P0..P3). Rectified cameras share K
  // and differ by a translation: P_i = K [I | t_i].
  std::array<Matrix34d, 4> projection = {Matrix34d::Zero(), Matrix34d::Zero(), Matrix34d::Zero(),
                                         Matrix34d::Zero()};
  Eigen::Matrix3d rect_from_cam0 = Eigen::Matrix3d::Identity();      // R0_rect
  Eigen::Isometry3d cam0_from_velo = Eigen::Isometry3d::Identity();  // Tr_velo_to_cam
  Eigen::Isometry3d velo_from_imu = Eigen::Isometry3d::Identity();   // Tr_imu_to_velo

  // --- Derived quantities for the stereo pair (cameras 2 and 3). ---

  // Focal length of camera 2 in pixels (P2(0,0); fx = fy for KITTI's rectified cameras).
  double FocalPx() const { return projection[2](0, 0); }
  // Principal point of camera 2 in pixels (P2(0,2), P2(1,2)).
  Eigen::Vector2d PrincipalPointPx() const { return {projection[2](0, 2), projection[2](1, 2)}; }
  // Centre of camera i in the rect frame, metres: -K^-1 * P_i.col(3). On KITTI, camera 2 sits about
  // 0.06 m left of camera 0 (x = -0.06) and camera 3 about 0.47 m right of it (x = +0.47).
  Eigen::Vector3d CameraCentreInRect(int camera) const;
  // Stereo baseline between cameras 2 and 3 in metres (about 0.54 m on KITTI), along rect x.
  double BaselineM() const;

  // --- Transforms. ---

  // velo -> rect: R0_rect * Tr_velo_to_cam.
  Eigen::Affine3d RectFromVelo() const;
  Eigen::Affine3d VeloFromRect() const { return RectFromVelo().inverse(); }

  // Projects a rect-frame point into camera `camera`'s image. Returns pixels; `depth_m` (optional)
  // receives the homogeneous scale, i.e. the point's depth in front of that camera. Points with
  // depth <= 0 are behind the camera and their pixels are meaningless; callers check depth.
  Eigen::Vector2d ProjectRectToImage(const Eigen::Vector3d& point_in_rect, int camera = 2,
                                     double* depth_m = nullptr) const;
  // Back-projects pixel (u, v) of camera `camera` at depth z (metres, along rect z) into rect.
  // Exact inverse of ProjectRectToImage for points in front of the camera.
  Eigen::Vector3d UnprojectImageToRect(const Eigen::Vector2d& pixel, double depth_m,
                                       int camera = 2) const;

  // Throws std::invalid_argument if the calibration cannot be used for stereo geometry: a camera
  // 2 or 3 projection with non-positive focal length, or cameras 2 and 3 at the same place.
  void CheckStereo() const;
};

// A KITTI-like calibration (the numbers of KITTI object frame 000000), for tests and synthetic
// data.
Calibration KittiLikeCalibration();

// Observation angle alpha (radians, in [-pi, pi)) of an object at rect-frame `location` with
// `rotation_y`: alpha = rotation_y - atan2(x, z), KITTI's definition.
double AlphaFromRotationY(double rotation_y, const Eigen::Vector3d& location);
// Inverse of AlphaFromRotationY: rotation_y = alpha + atan2(x, z), in [-pi, pi).
double RotationYFromAlpha(double alpha, const Eigen::Vector3d& location);
// Wraps an angle into [-pi, pi).
double WrapAngle(double angle_rad);

// Stereo depth uncertainty: the depth error (m) caused by a disparity error of `disparity_error_px`
// at depth `depth_m`, to first order: dz = z^2 / (b f) * dd.
double StereoDepthError(double depth_m, double baseline_m, double focal_px,
                        double disparity_error_px);

}  // namespace stereodet

#endif  // STEREODET_GEOMETRY_CALIBRATION_H_
