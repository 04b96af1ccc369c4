#include "stereodet/stereo/planar_scene.h"

#include <cmath>
#include <cstdint>
#include <opencv2/core/utility.hpp>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

// Lattice hash -> [0, 1).
double Hash(int64_t x, int64_t y, unsigned seed) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ULL ^
               (static_cast<uint64_t>(y) + 0x632BE59BD9B4E019ULL) * 0xC2B2AE3D27D4EB4FULL ^ seed;
  h ^= h >> 31;
  h *= 0xBF58476D1CE4E5B9ULL;
  h ^= h >> 29;
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

// Smoothly interpolated value noise, continuous in (x, y).
double ValueNoise(double x, double y, unsigned seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  double tx = x - fx, ty = y - fy;
  tx = tx * tx * (3 - 2 * tx);
  ty = ty * ty * (3 - 2 * ty);
  const double a = Hash(ix, iy, seed), b = Hash(ix + 1, iy, seed), c = Hash(ix, iy + 1, seed),
               d = Hash(ix + 1, iy + 1, seed);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

// Three octaves from `scale` up: detail for matching near, structure far.
double Texture(double x, double y, double scale, unsigned seed) {
  return 0.5 * ValueNoise(x / scale, y / scale, seed) +
         0.3 * ValueNoise(x / (4 * scale), y / (4 * scale), seed + 1) +
         0.2 * ValueNoise(x / (16 * scale), y / (16 * scale), seed + 2);
}

struct Hit {
  double t = -1;  // ray parameter (= depth in front of the camera, the ray having z = 1)
  cv::Vec3b colour{0, 0, 0};
};

Hit CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
            const GroundPlane& ground, const PlanarSceneOptions& options) {
  Hit hit;
  const double denominator = ground.normal_in_rect.dot(direction);
  if (std::abs(denominator) > 1e-12) {
    const double t = -ground.HeightAbove(origin) / denominator;
    if (t > 0) hit.t = t;
  }
  bool on_wall = false;
  if (options.wall_depth_m > 0) {
    const double t = (options.wall_depth_m - origin.z()) / direction.z();
    if (t > 0 && (hit.t < 0 || t < hit.t)) {
      hit.t = t;
      on_wall = true;
    }
  }
  if (hit.t < 0) {  // sky: a smooth vertical gradient, no texture to match
    const double elevation = -direction.y();
    const auto blue = static_cast<uint8_t>(std::clamp(200 + 100 * elevation, 0.0, 255.0));
    hit.colour = cv::Vec3b(blue, 180, 150);
    return hit;
  }
  const Eigen::Vector3d point = origin + hit.t * direction;
  const double s = options.texture_scale_m;
  // Ground texture in the plane's own coordinates (x and along-road z), wall texture in (x, y).
  const double tx = point.x(), ty = on_wall ? point.y() : point.z();
  const unsigned seed = options.seed * 7 + (on_wall ? 3 : 0);
  const double grey = Texture(tx, ty, s, seed);
  const double tint_r = Texture(tx, ty, 8 * s, seed + 11),
               tint_b = Texture(tx, ty, 8 * s, seed + 13);
  auto to8 = [](double value) {
    return static_cast<uint8_t>(std::clamp(255.0 * value, 0.0, 255.0));
  };
  hit.colour = cv::Vec3b(to8(0.15 + 0.7 * grey * (0.8 + 0.4 * tint_b)),   // B
                         to8(0.15 + 0.7 * grey),                          // G
                         to8(0.15 + 0.7 * grey * (0.8 + 0.4 * tint_r)));  // R
  return hit;
}

}  // namespace

void PlanarSceneOptions::Check() const {
  STEREODET_CHECK(width_px >= 16 && height_px >= 16) << "scene image must be at least 16x16";
  STEREODET_CHECK(camera_height_m > 0) << "camera height must be > 0";
  STEREODET_CHECK(std::abs(ground_pitch_deg) < 45 && std::abs(ground_roll_deg) < 45)
      << "ground pitch and roll must be within +-45 deg";
  STEREODET_CHECK(wall_depth_m >= 0) << "wall depth must be >= 0";
  STEREODET_CHECK(texture_scale_m > 0) << "texture scale must be > 0";
}

PlanarScene RenderPlanarScene(const Calibration& calib, const PlanarSceneOptions& options) {
  options.Check();
  const StereoGeometry geometry = StereoGeometry::FromCalibration(calib);
  PlanarScene scene;
  const Eigen::Matrix3d tilt =
      (Eigen::AngleAxisd(options.ground_pitch_deg * M_PI / 180, Eigen::Vector3d::UnitX()) *
       Eigen::AngleAxisd(options.ground_roll_deg * M_PI / 180, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  // Rect y points down; rotating about +x by a positive angle tips the up normal (0,-1,0) towards
  // -z, i.e. the road rises ahead.
  scene.ground.normal_in_rect = tilt * Eigen::Vector3d(0, -1, 0);
  scene.ground.offset_m = options.camera_height_m;

  const int rows = options.height_px, cols = options.width_px;
  scene.left_bgr.create(rows, cols, CV_8UC3);
  scene.right_bgr.create(rows, cols, CV_8UC3);
  scene.disparity_px.create(rows, cols, CV_32FC1);
  const Eigen::Vector3d c2 = calib.CameraCentreInRect(2), c3 = calib.CameraCentreInRect(3);
  const Eigen::Matrix3d k_inverse = calib.projection[2].leftCols<3>().inverse();
  const Eigen::Matrix3d k3_inverse = calib.projection[3].leftCols<3>().inverse();
  cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      for (int u = 0; u < cols; ++u) {
        const Eigen::Vector3d ray2 = k_inverse * Eigen::Vector3d(u, v, 1);
        const Eigen::Vector3d ray3 = k3_inverse * Eigen::Vector3d(u, v, 1);
        const Hit left = CastRay(c2, ray2 / ray2.z(), scene.ground, options);
        const Hit right = CastRay(c3, ray3 / ray3.z(), scene.ground, options);
        scene.left_bgr.at<cv::Vec3b>(v, u) = left.colour;
        scene.right_bgr.at<cv::Vec3b>(v, u) = right.colour;
        scene.disparity_px.at<float>(v, u) =
            left.t > 0 ? static_cast<float>(geometry.DisparityFromDepth(left.t))
                       : kInvalidDisparity;
      }
    }
  });
  return scene;
}

void PlanarSceneDatasetOptions::Check() const {
  STEREODET_CHECK_GE(frames, 1);
  STEREODET_CHECK(width_px >= 1 && width_px <= 1242 && height_px >= 1 && height_px <= 375)
      << "scene dataset images must be at most KITTI's 1242x375, got " << width_px << "x"
      << height_px;
}

std::vector<std::string> WritePlanarSceneDataset(const std::filesystem::path& root,
                                                 const PlanarSceneDatasetOptions& options) {
  options.Check();
  Calibration calib = KittiLikeCalibration();
  // Keep KITTI's principal point centred in a smaller image: shift every P_i in pixels.
  Eigen::Matrix3d shift = Eigen::Matrix3d::Identity();
  shift(0, 2) = -(1242 - options.width_px) / 2.0;
  shift(1, 2) = -(375 - options.height_px) / 2.0;
  for (Matrix34d& projection : calib.projection) projection = shift * projection;
  const std::filesystem::path training = root / "training";
  std::vector<std::string> ids;
  for (int i = 0; i < options.frames; ++i) {
    const std::string id = FrameId(i);
    PlanarSceneOptions scene_options;
    scene_options.width_px = options.width_px;
    scene_options.height_px = options.height_px;
    scene_options.seed = static_cast<unsigned>(i + 1);
    scene_options.wall_depth_m = 15.0 + 10.0 * (i % 3);
    scene_options.ground_pitch_deg = 0.5 * (i % 3) - 0.5;
    const PlanarScene scene = RenderPlanarScene(calib, scene_options);
    WriteImageAtomically(training / "image_2" / (id + ".png"), scene.left_bgr);
    WriteImageAtomically(training / "image_3" / (id + ".png"), scene.right_bgr);
    std::filesystem::create_directories(training / "disp_noc_0");
    WriteKittiDisparity(training / "disp_noc_0" / (id + ".png"), scene.disparity_px);
    WriteCalibration(training / "calib" / (id + ".txt"), calib);
    ids.push_back(id);
  }
  WriteSplit(root / "ImageSets" / "all.txt", ids);
  return ids;
}

}  // namespace stereodet
