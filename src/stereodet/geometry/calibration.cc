#include "stereodet/geometry/calibration.h"

#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

Eigen::Vector3d Calibration::CameraCentreInRect(int camera) const {
  STEREODET_CHECK(camera >= 0 && camera < 4) << "camera must be 0..3, got " << camera;
  const Matrix34d& p = projection[camera];
  const Eigen::Matrix3d k = p.leftCols<3>();
  // P = K [I | t]  =>  t = K^-1 P.col(3), and the camera centre is -t.
  return -k.inverse() * p.col(3);
}

double Calibration::BaselineM() const {
  return (CameraCentreInRect(3) - CameraCentreInRect(2)).x();
}

Eigen::Affine3d Calibration::RectFromVelo() const {
  Eigen::Affine3d rect_from_cam0_affine = Eigen::Affine3d::Identity();
  rect_from_cam0_affine.linear() = rect_from_cam0;
  return rect_from_cam0_affine * cam0_from_velo;
}

Eigen::Vector2d Calibration::ProjectRectToImage(const Eigen::Vector3d& point_in_rect, int camera,
                                                double* depth_m) const {
  STEREODET_CHECK(camera >= 0 && camera < 4) << "camera must be 0..3, got " << camera;
  const Eigen::Vector3d h = projection[camera] * point_in_rect.homogeneous();
  if (depth_m != nullptr) *depth_m = h.z();
  return h.head<2>() / h.z();
}

Eigen::Vector3d Calibration::UnprojectImageToRect(const Eigen::Vector2d& pixel, double depth_m,
                                                  int camera) const {
  STEREODET_CHECK(camera >= 0 && camera < 4) << "camera must be 0..3, got " << camera;
  // Solve P [X; 1] = depth * [u; v; 1] for X: K X = depth * [u; v; 1] - P.col(3).
  const Matrix34d& p = projection[camera];
  const Eigen::Vector3d rhs = depth_m * Eigen::Vector3d(pixel.x(), pixel.y(), 1.0) - p.col(3);
  return p.leftCols<3>().partialPivLu().solve(rhs);
}

void Calibration::CheckStereo() const {
  for (int camera : {2, 3}) {
    STEREODET_CHECK(projection[camera](0, 0) > 0 && projection[camera](1, 1) > 0)
        << "calibration: P" << camera << " has a non-positive focal length";
  }
  STEREODET_CHECK(std::abs(BaselineM()) > 1e-6)
      << "calibration: cameras 2 and 3 are at the same place (P2 and P3 give no baseline)";
}

Calibration KittiLikeCalibration() {
  Calibration calib;
  calib.projection[0] << 7.215377e+02, 0.0, 6.095593e+02, 0.0,  //
      0.0, 7.215377e+02, 1.728540e+02, 0.0,                     //
      0.0, 0.0, 1.0, 0.0;
  calib.projection[1] << 7.215377e+02, 0.0, 6.095593e+02, -3.875744e+02,  //
      0.0, 7.215377e+02, 1.728540e+02, 0.0,                               //
      0.0, 0.0, 1.0, 0.0;
  calib.projection[2] << 7.215377e+02, 0.0, 6.095593e+02, 4.485728e+01,  //
      0.0, 7.215377e+02, 1.728540e+02, 2.163791e-01,                     //
      0.0, 0.0, 1.0, 2.745884e-03;
  calib.projection[3] << 7.215377e+02, 0.0, 6.095593e+02, -3.395242e+02,  //
      0.0, 7.215377e+02, 1.728540e+02, 2.199936e+00,                      //
      0.0, 0.0, 1.0, 2.729905e-03;
  calib.rect_from_cam0 << 9.999239e-01, 9.837760e-03, -7.445048e-03,  //
      -9.869795e-03, 9.999421e-01, -4.278459e-03,                     //
      7.402527e-03, 4.351614e-03, 9.999631e-01;
  Eigen::Matrix4d velo = Eigen::Matrix4d::Identity();
  velo.topRows<3>() << 7.533745e-03, -9.999714e-01, -6.166020e-04, -4.069766e-03,  //
      1.480249e-02, 7.280733e-04, -9.998902e-01, -7.631618e-02,                    //
      9.998621e-01, 7.523790e-03, 1.480755e-02, -2.717806e-01;
  calib.cam0_from_velo.matrix() = velo;
  Eigen::Matrix4d imu = Eigen::Matrix4d::Identity();
  imu.topRows<3>() << 9.999976e-01, 7.553071e-04, -2.035826e-03, -8.086759e-01,  //
      -7.854027e-04, 9.998898e-01, -1.482298e-02, 3.195559e-01,                  //
      2.024406e-03, 1.482454e-02, 9.998881e-01, -7.997231e-01;
  calib.velo_from_imu.matrix() = imu;
  return calib;
}

double WrapAngle(double angle_rad) {
  double wrapped = std::fmod(angle_rad + M_PI, 2.0 * M_PI);
  if (wrapped < 0) wrapped += 2.0 * M_PI;
  return wrapped - M_PI;
}

double AlphaFromRotationY(double rotation_y, const Eigen::Vector3d& location) {
  return WrapAngle(rotation_y - std::atan2(location.x(), location.z()));
}

double RotationYFromAlpha(double alpha, const Eigen::Vector3d& location) {
  return WrapAngle(alpha + std::atan2(location.x(), location.z()));
}

double StereoDepthError(double depth_m, double baseline_m, double focal_px,
                        double disparity_error_px) {
  STEREODET_CHECK(baseline_m > 0 && focal_px > 0)
      << "baseline and focal length must be positive, got " << baseline_m << " m, " << focal_px
      << " px";
  return depth_m * depth_m / (baseline_m * focal_px) * disparity_error_px;
}

}  // namespace stereodet
