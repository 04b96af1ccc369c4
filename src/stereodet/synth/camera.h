// The synthetic stereo cameras: KITTI-like calibration at any resolution, ray-cast rendering of
// left/right images with depth and object-id buffers, and exact ground-truth disparity.
#ifndef STEREODET_SYNTH_CAMERA_H_
#define STEREODET_SYNTH_CAMERA_H_

#include <cstdint>
#include <opencv2/core.hpp>

#include "stereodet/geometry/calibration.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

// KITTI-like calibration (geometry::KittiLikeCalibration(): focal 721.5377 px, principal point
// (609.56, 172.85), P2's small offset, baseline 0.532 m, KITTI's R0_rect and Tr_velo_to_cam) for an
// image of width x height pixels. The intrinsics are scaled by width / 1242 (square pixels, same
// horizontal field of view); the principal point's row is scaled by height / 375 so the horizon
// keeps its relative place. The camera centres (the translations of P0..P3 in metres) are kept.
// Pixel centres are at integer coordinates (OpenCV's and KITTI's convention).
// Requires: width, height >= 8.
Calibration SynthCalibration(int width, int height);

struct RenderOptions {
  bool shadows = true;                // cast a shadow ray towards the sun for every lit pixel
  float shadow_distance_m = 80.0f;    // farther blockers cast no shadow (saves time; haze hides it)
  float optics_blur_sigma_px = 0.5f;  // Gaussian blur of the lens (0 = none)
  float vignetting = 0.25f;           // relative brightness lost in the image corners, [0, 1)
  float noise_sigma = 1.5f;           // sensor noise, standard deviation in 8-bit grey levels
  float max_depth_m = 300.0f;         // hits farther than this count as no hit in the depth buffer

  void Check() const;  // throws std::invalid_argument
};

struct CameraRender {
  cv::Mat image;      // CV_8UC3, BGR (as cv::imwrite expects)
  cv::Mat depth;      // CV_32FC1, depth (m) of the hit in front of this camera, 0 = no hit (sky)
  cv::Mat object_id;  // CV_32SC1, Scene::objects index of the hit, -1 = none (if requested)
  cv::Mat points;     // CV_32FC3, rect-frame hit points, NaN = none (if requested)
};

struct RenderRequest {
  int camera = 2;  // 2 = left colour camera, 3 = right
  int width = 1242;
  int height = 375;
  float gain = 1.0f;  // per-camera gain (KITTI's two cameras differ slightly in brightness)
  uint64_t noise_seed = 0;
  bool object_ids = false;
  bool points = false;
};

// Ray casts `scene` through every pixel centre of camera `request.camera` of `calib`.
// Deterministic: the sensor noise is a hash of (noise_seed, camera, pixel).
CameraRender RenderCamera(const Scene& scene, const Calibration& calib,
                          const RenderRequest& request, const RenderOptions& options = {});

struct GroundTruthDisparityOptions {
  // A left pixel counts as visible in the right image ("noc", non-occluded) when the right depth
  // buffer at its match (either neighbouring column) is within this tolerance of its depth.
  float depth_tolerance_rel = 0.02f;
  float depth_tolerance_abs_m = 0.05f;
  void Check() const;
};

// Ground-truth disparity of the left image (camera 2) in pixels, u2 - u3 of the left hit point
// projected by P2 and P3, for pixels whose point is seen by the right camera; 0 elsewhere (sky,
// occluded in or outside the right image). Requires left.points and right.depth.
cv::Mat GroundTruthDisparity(const Calibration& calib, const CameraRender& left,
                             const CameraRender& right,
                             const GroundTruthDisparityOptions& options = {});

// KITTI's stereo format: uint16, round(disparity * 256), 0 = no ground truth; positive disparities
// below 1/256 px become 1, above 255.99 px are clamped.
cv::Mat EncodeKittiDisparity(const cv::Mat& disparity_px);
// Inverse: CV_32FC1 disparity in pixels, 0 = no ground truth.
cv::Mat DecodeKittiDisparity(const cv::Mat& encoded);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_CAMERA_H_
