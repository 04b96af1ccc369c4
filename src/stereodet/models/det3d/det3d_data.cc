#include "stereodet/models/det3d/det3d_data.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/check.h"

namespace stereodet {

const char* PointSourceName(PointSource source) {
  return source == PointSource::kLidar ? "lidar" : "stereo";
}

std::optional<PointSource> ParsePointSource(std::string_view text) {
  if (text == "lidar") return PointSource::kLidar;
  if (text == "stereo") return PointSource::kStereo;
  return std::nullopt;
}

void PointFilterOptions::Check() const {
  STEREODET_CHECK(stereo_max_distance_m >= 0.0 && std::isfinite(stereo_max_distance_m))
      << "stereo max distance must be >= 0, got " << stereo_max_distance_m;
}

std::filesystem::path PointsPath(const KittiDataset& dataset,
                                 const std::filesystem::path& stereo_points_dir, PointSource source,
                                 const std::string& id) {
  if (source == PointSource::kLidar) return dataset.Paths(id).velodyne;
  STEREODET_CHECK(!stereo_points_dir.empty())
      << "stereo input needs --points (the folder `stereodet stereo --encode points` wrote)";
  return stereo_points_dir / "velodyne" / (id + ".bin");
}

std::vector<VeloPoint> FilterDet3dPoints(const std::vector<VeloPoint>& raw,
                                         const Calibration& calib, int image_width,
                                         int image_height, PointSource source,
                                         const BevGridOptions& grid,
                                         const PointFilterOptions& filter) {
  const Eigen::Affine3d rect_from_velo = calib.RectFromVelo();
  std::vector<VeloPoint> points;
  points.reserve(raw.size());
  for (const VeloPoint& p : raw) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
        !std::isfinite(p.reflectance)) {
      continue;
    }
    if (filter.crop_to_grid && !grid.Contains(p.x, p.y, p.z)) continue;
    if (source == PointSource::kStereo) {
      if (filter.stereo_max_distance_m > 0 && std::hypot(p.x, p.y) > filter.stereo_max_distance_m) {
        continue;
      }
    } else if (filter.camera_fov_only) {
      double depth = 0;
      const Eigen::Vector2d px =
          calib.ProjectRectToImage(rect_from_velo * Eigen::Vector3d(p.x, p.y, p.z), 2, &depth);
      if (depth <= 0 || px.x() < 0 || px.y() < 0 || px.x() >= image_width ||
          px.y() >= image_height) {
        continue;
      }
    }
    points.push_back(p);
  }
  // A training holds every frame: give back what the filters freed (a LiDAR scan keeps ~15% of
  // its points after the camera-view cut; the reserve above was for all of them).
  points.shrink_to_fit();
  return points;
}

Det3dFrame LoadDet3dFrame(const KittiDataset& dataset,
                          const std::filesystem::path& stereo_points_dir, PointSource source,
                          const std::string& id, const std::vector<std::string>& classes,
                          const BevGridOptions& grid, const PointFilterOptions& filter,
                          bool with_labels) {
  filter.Check();
  grid.Check();
  const FramePaths paths = dataset.Paths(id);
  Det3dFrame frame;
  frame.id = id;
  frame.calib = ReadCalibration(paths.calib);
  std::tie(frame.image_width, frame.image_height) = PngImageSize(paths.image_left);
  frame.points =
      FilterDet3dPoints(ReadVelodyne(PointsPath(dataset, stereo_points_dir, source, id)),
                        frame.calib, frame.image_width, frame.image_height, source, grid, filter);
  if (with_labels) {
    for (const Object& o : ReadObjects(paths.label).objects) {
      const auto it = std::find(classes.begin(), classes.end(), o.type);
      if (it == classes.end() || !o.Has3D()) continue;
      LidarBox box = LidarBoxFromObject(o, frame.calib);
      box.label = static_cast<int>(it - classes.begin());
      frame.boxes.push_back(box);
    }
  }
  return frame;
}

void Det3dAugmentOptions::Check() const {
  STEREODET_CHECK(global_rotation_rad >= 0 && global_rotation_rad <= M_PI)
      << "global rotation must be in [0, pi], got " << global_rotation_rad;
  STEREODET_CHECK(global_scale_min > 0 && global_scale_min <= global_scale_max)
      << "global scale range must be 0 < min <= max, got [" << global_scale_min << ", "
      << global_scale_max << "]";
  STEREODET_CHECK(object_translation_sigma_m >= 0 && std::isfinite(object_translation_sigma_m))
      << "object translation sigma must be >= 0, got " << object_translation_sigma_m;
  STEREODET_CHECK(object_rotation_rad >= 0 && object_rotation_rad <= M_PI)
      << "object rotation must be in [0, pi], got " << object_rotation_rad;
}

Det3dFrame AugmentFrame(const Det3dFrame& frame, const Det3dAugmentOptions& options,
                        uint64_t seed) {
  options.Check();
  Det3dFrame out = frame;
  if (!options.enabled) return out;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };

  // Per object: move a box and its points, unless it then collides with another box.
  std::vector<char> moved(out.points.size(), 0);
  for (size_t b = 0; b < out.boxes.size(); ++b) {
    const LidarBox old = out.boxes[b];
    std::normal_distribution<double> shift(0.0,
                                           std::max(1e-12, options.object_translation_sigma_m));
    LidarBox moved_box = old;
    const double dx = options.object_translation_sigma_m > 0 ? shift(rng) : 0.0;
    const double dy = options.object_translation_sigma_m > 0 ? shift(rng) : 0.0;
    const double dyaw = uniform(-options.object_rotation_rad, options.object_rotation_rad);
    moved_box.x += dx;
    moved_box.y += dy;
    moved_box.yaw += dyaw;
    bool collides = false;
    for (size_t o = 0; o < out.boxes.size() && !collides; ++o) {
      collides = o != b && LidarBevIou(moved_box, out.boxes[o]) > 0.0;
    }
    if (collides) continue;
    const double c = std::cos(dyaw), s = std::sin(dyaw);
    for (size_t i = 0; i < out.points.size(); ++i) {
      VeloPoint& p = out.points[i];
      if (moved[i] || !PointInBox(old, p.x, p.y, p.z)) continue;
      const double rx = p.x - old.x, ry = p.y - old.y;
      p.x = static_cast<float>(old.x + c * rx - s * ry + dx);
      p.y = static_cast<float>(old.y + s * rx + c * ry + dy);
      moved[i] = 1;
    }
    out.boxes[b] = moved_box;
  }

  // Global: flip y, rotate about z, scale.
  const bool flip = options.flip && unit(rng) < 0.5;
  const double angle = uniform(-options.global_rotation_rad, options.global_rotation_rad);
  const double scale = uniform(options.global_scale_min, options.global_scale_max);
  const double c = std::cos(angle), s = std::sin(angle);
  auto transform = [&](double& x, double& y, double& z) {
    if (flip) y = -y;
    const double nx = c * x - s * y, ny = s * x + c * y;
    x = nx * scale;
    y = ny * scale;
    z *= scale;
  };
  for (VeloPoint& p : out.points) {
    double x = p.x, y = p.y, z = p.z;
    transform(x, y, z);
    p.x = static_cast<float>(x);
    p.y = static_cast<float>(y);
    p.z = static_cast<float>(z);
  }
  for (LidarBox& b : out.boxes) {
    transform(b.x, b.y, b.z);
    if (flip) b.yaw = -b.yaw;
    b.yaw = WrapAngle(b.yaw + angle);
    b.l *= scale;
    b.w *= scale;
    b.h *= scale;
  }
  return out;
}

}  // namespace stereodet
