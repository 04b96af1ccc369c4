// Geometry from disparity with a KITTI calibration: depth, 3D points in the rect and velo frames,
// the ground plane, height above the ground, and the quantized depth and height images.
//
// The stereo pair is cameras 2 (left) and 3 (right). KITTI's rectified cameras share K and differ
// by a translation, P_i = K [I | t_i], so camera i sits at c_i = -K^-1 P_i.col(3) in the rect
// frame. A point X seen at pixel (u, v) of camera 2 with disparity d = u_2 - u_3 > 0 has
//   z = f b / d                     (its depth in front of camera 2, metres; f = P2(0,0),
//                                    b = c_3.x - c_2.x = Calibration::BaselineM())
//   X = c_2 + z K^-1 [u, v, 1]^T     (rect frame; c_2 is about 6 cm left of the rect origin on
//   KITTI)
// which is the exact inverse of Calibration::ProjectRectToImage for cameras 2 and 3 (up to KITTI's
// ~15 micrometre difference between the cameras' z offsets).
#ifndef STEREODET_STEREO_REPROJECTION_H_
#define STEREODET_STEREO_REPROJECTION_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <string>

#include "stereodet/geometry/calibration.h"

namespace stereodet {

// The numbers the per-pixel reprojection needs, taken once from a Calibration.
struct StereoGeometry {
  double focal_px = 0;  // f: P2(0,0) (= P2(1,1)); the horizontal focal length
  // The vertical focal length, px; 0 = focal_px (square pixels, as KITTI's). Only a geometry
  // Scaled() by different factors across and down (an image resized to a rounded size) has its own.
  double focal_y_px = 0;
  double baseline_m = 0;        // b: camera 3's centre minus camera 2's, along rect x
  double cx_px = 0, cy_px = 0;  // principal point of camera 2
  Eigen::Vector3d camera2_in_rect = Eigen::Vector3d::Zero();  // c_2
  Eigen::Affine3d velo_from_rect = Eigen::Affine3d::Identity();

  // Throws std::invalid_argument (Calibration::CheckStereo) for a calibration without a stereo
  // pair.
  static StereoGeometry FromCalibration(const Calibration& calib);

  // f b / d, metres in front of camera 2. Requires: disparity_px > 0.
  double DepthFromDisparity(double disparity_px) const {
    return focal_px * baseline_m / disparity_px;
  }
  double DisparityFromDepth(double depth_m) const { return focal_px * baseline_m / depth_m; }
  double FocalY() const { return focal_y_px > 0 ? focal_y_px : focal_px; }
  // The geometry of the images resized by (scale_x, scale_y) (new size / old size): focal lengths
  // scaled (f_x by scale_x, f_y by scale_y), the principal point mapped as pixel centres are by
  // OpenCV's resize (c' = (c + 0.5) scale - 0.5), the baseline and the frames unchanged. A
  // disparity in the resized left image is then in resized pixels: z = f_x' b / d' is the same
  // depth as z = f b / d at full size. Requires scales > 0.
  StereoGeometry Scaled(double scale_x, double scale_y) const;
  // X = c_2 + z K^-1 [u, v, 1]: pixel (u, v) of the left image at disparity d, in the rect frame.
  Eigen::Vector3d PointInRect(double u_px, double v_px, double disparity_px) const;
};

// Depth image: CV_32FC1 metres (f b / d) for valid disparities, NaN elsewhere.
cv::Mat DepthFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry);
// Points image: CV_32FC3 (x, y, z) in the rect frame for valid disparities, NaN elsewhere.
cv::Mat PointsInRectFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry);

// --- Ground plane. ---

// A plane n . X + offset = 0 in the rect frame with unit normal n pointing up (negative rect y), so
// that HeightAbove(X) = n . X + offset is the height of X above the ground in metres.
struct GroundPlane {
  Eigen::Vector3d normal_in_rect{0.0, -1.0, 0.0};
  double offset_m = 1.65;
  double HeightAbove(const Eigen::Vector3d& point_in_rect) const {
    return normal_in_rect.dot(point_in_rect) + offset_m;
  }
  // The flat ground `camera_height_m` below the rect origin (KITTI's camera 0 is 1.65 m up).
  static GroundPlane Nominal(double camera_height_m);
};

struct GroundPlaneOptions {
  // Pixels considered: rows in the lower `roi_fraction` of the image, every `sample_step_px`-th row
  // and column, with depth in [min_depth_m, max_depth_m] (BM is precise there), at most
  // `max_samples` of them (evenly thinned). Beyond ~20 m BM's depth noise on the slanted road and
  // the feet of walls and cars bias the fit (measured: docs/stereo.md).
  double roi_fraction = 0.5;
  int sample_step_px = 4;
  double min_depth_m = 3.0;
  double max_depth_m = 20.0;
  // Only points within this distance of the camera's vertical plane (|x - c2.x| in rect; 0 = no
  // limit): the road ahead, not the kerbs, sidewalks and parked cars at its sides.
  double max_lateral_m = 6.0;
  int max_samples = 3000;
  // RANSAC: `iterations` random 3-point planes; inliers within `inlier_threshold_m`; the best plane
  // is refined by least squares on its inliers. Seeded, so results are deterministic.
  int iterations = 100;
  double inlier_threshold_m = 0.05;
  unsigned seed = 42;
  // Acceptance: the fit is used only if it has >= min_inliers inliers, >= min_inlier_fraction of
  // the samples, a normal within max_tilt_deg of vertical (pitch and roll of the car on its springs
  // and of the road), and the rect origin between min and max_camera_height_m above it. Otherwise
  // the nominal plane (flat road, camera `nominal_camera_height_m` up) is used.
  int min_inliers = 200;
  double min_inlier_fraction = 0.2;
  double max_tilt_deg = 10.0;
  double min_camera_height_m = 1.0;
  double max_camera_height_m = 2.5;
  double nominal_camera_height_m = 1.65;  // KITTI's camera height
  bool enabled = true;                    // false: always the nominal plane
  // Tolerance of an accepted fit (docs/stereo.md): on a flat road a level camera's ground is within
  // about a degree of rect -y (KITTI's pitch on its springs) and the camera at its nominal height
  // within a few centimetres. An accepted fit tilted more than warn_tilt_deg, or whose camera
  // height differs from nominal_camera_height_m by more than warn_camera_height_m, is `suspect`:
  // reported and warned about, and with suspect_uses_prior replaced by the prior (the nominal
  // mounting plane). The default keeps the fit, as before.
  double warn_tilt_deg = 1.5;
  double warn_camera_height_m = 0.25;
  bool suspect_uses_prior = false;
  void Check() const;
};

struct GroundPlaneFit {
  GroundPlane plane;    // the fit, or the nominal plane when !fitted
  bool fitted = false;  // true: RANSAC's plane was accepted; false: the fallback was used
  std::string reason;   // "fitted" or why the fallback was used ("too few samples (12 < 200)")
  int samples = 0;      // points RANSAC saw
  int inliers = 0;      // inliers of the accepted fit (0 for the fallback)
  double camera_height_m = 0;  // height of the rect origin above `plane`
  double tilt_deg = 0;         // angle between the plane normal and rect -y
  // The RANSAC fit passed acceptance but lies beyond the warning tolerance (GroundPlaneOptions);
  // `fitted` is then false when suspect_uses_prior replaced it by the nominal plane.
  bool suspect = false;
  // inliers / samples of the accepted fit (0 for a fallback).
  double InlierFraction() const { return samples > 0 ? static_cast<double>(inliers) / samples : 0; }
};

// Fits the ground to the stereo points of the lower image. Never throws for bad data: it falls
// back. `disparity_px` is CV_32FC1 pixels, or OpenCV's raw CV_16SC1 (pixels x 16, <= 0 invalid).
GroundPlaneFit FitGroundPlane(const cv::Mat& disparity_px, const StereoGeometry& geometry,
                              const GroundPlaneOptions& options = {});

// Height above `plane` per pixel: CV_32FC1 metres, NaN where the disparity is invalid.
cv::Mat HeightFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry,
                            const GroundPlane& plane);

// --- Quantization into the pixel domain. Value 0 is reserved for "no stereo here". ---

// Height in metres clipped to [min_m, max_m] and mapped linearly onto 1..511 (9 bits):
// q = 1 + round((clamp(h) - min_m) / (max_m - min_m) * 510). Default step: 5 m / 510 = 9.8 mm.
struct HeightQuantization {
  double min_m = -1.0;                 // below the road: stereo noise, kerbs, ditches
  double max_m = 4.0;                  // above every KITTI object class (trucks and trams excepted)
  static constexpr int kLevels = 511;  // largest code
  void Check() const;
  uint16_t Quantize(double height_m) const;  // NaN -> 0
  double Dequantize(uint16_t code) const;    // 0 -> NaN
};

// Depth in metres clipped to [min_m, max_m] and mapped linearly onto 1..2^bits - 1.
// Default: 0..80 m in 16 bits, a step of 1.2 mm.
struct DepthQuantization {
  double min_m = 0.0;
  double max_m = 80.0;
  int bits = 16;  // 8..16
  void Check() const;
  int MaxCode() const { return (1 << bits) - 1; }
  uint16_t Quantize(double depth_m) const;  // NaN -> 0
  double Dequantize(uint16_t code) const;   // 0 -> NaN
};

// CV_16UC1 images of the codes above (0 where the input is NaN).
cv::Mat QuantizeHeight(const cv::Mat& height_m, const HeightQuantization& quantization);
cv::Mat QuantizeDepth(const cv::Mat& depth_m, const DepthQuantization& quantization);

}  // namespace stereodet

#endif  // STEREODET_STEREO_REPROJECTION_H_
