// A textured road-and-wall scene rendered for both stereo cameras with its exact disparity: a
// stand-in for real stereo pairs in tests, the benchmark and demos (the full synthetic-KITTI
// generator lives in the synth module).
//
// The scene, in the rect frame: a ground plane `camera_height_m` below the rect origin, pitched by
// `ground_pitch_deg` and rolled by `ground_roll_deg`, and optionally a fronto-parallel wall at
// depth `wall_depth_m` (rect z). Both carry a multi-octave value-noise texture fixed to the world,
// so that the two cameras see the same surface; rays that hit nothing show a smooth sky.
#ifndef STEREODET_STEREO_PLANAR_SCENE_H_
#define STEREODET_STEREO_PLANAR_SCENE_H_

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/stereo/reprojection.h"

namespace stereodet {

struct PlanarSceneOptions {
  int width_px = 1242, height_px = 375;  // KITTI's image size
  double camera_height_m = 1.65;         // rect origin above the ground
  double ground_pitch_deg = 0.0;  // rotation of the ground about rect x (positive: rises ahead)
  double ground_roll_deg = 0.0;   // rotation of the ground about rect z
  double wall_depth_m = 30.0;     // 0 = no wall
  double texture_scale_m = 0.05;  // finest texture period, metres
  unsigned seed = 1;
  void Check() const;
};

struct PlanarScene {
  cv::Mat left_bgr, right_bgr;  // CV_8UC3 images of cameras 2 and 3
  cv::Mat disparity_px;         // CV_32FC1 exact left disparity; kInvalidDisparity on the sky
  GroundPlane ground;           // the true ground plane
};

PlanarScene RenderPlanarScene(const Calibration& calib, const PlanarSceneOptions& options = {});

// A tiny KITTI-layout dataset of such scenes (`stereodet stereo scene`), for trying the stereo
// pipeline and for tests that should not depend on the full generator (`stereodet synth`).
struct PlanarSceneDatasetOptions {
  int frames = 2;
  // Image size, px, at most KITTI's 1242 x 375: KITTI-like cameras whose principal point stays
  // centred in the smaller image.
  int width_px = 1242, height_px = 375;
  void Check() const;  // throws std::invalid_argument
};

// Writes ROOT/training/{image_2,image_3,disp_noc_0}/ID.png (disparity exact, in KITTI's stereo
// format), ROOT/training/calib/ID.txt and ROOT/ImageSets/all.txt, each file atomically. Frame i
// (ID = FrameId(i)) has seed i + 1, its wall at 15 + 10 (i mod 3) m and its ground pitched by
// 0.5 (i mod 3) - 0.5 deg. Returns the ids, in order.
std::vector<std::string> WritePlanarSceneDataset(const std::filesystem::path& root,
                                                 const PlanarSceneDatasetOptions& options = {});

}  // namespace stereodet

#endif  // STEREODET_STEREO_PLANAR_SCENE_H_
