// Frames of the 3D detector (issue 14): points (LiDAR scans or stereo point clouds, velodyne
// frame) and ground-truth boxes read from a KITTI-format dataset, and the augmentation of a
// training frame. Torch-free.
#ifndef STEREODET_MODELS_DET3D_DET3D_DATA_H_
#define STEREODET_MODELS_DET3D_DET3D_DATA_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/models/det3d/det3d_boxes.h"
#include "stereodet/models/det3d/det3d_targets.h"

namespace stereodet {

enum class PointSource { kLidar, kStereo };
const char* PointSourceName(PointSource source);  // "lidar", "stereo"
std::optional<PointSource> ParsePointSource(std::string_view text);

struct PointFilterOptions {
  // LiDAR: keep only points that project into the left image (camera 2) in front of it, as SA-SSD
  // trains (KITTI labels only objects in that view).
  bool camera_fov_only = true;
  // Stereo: drop points farther than this from the sensor (horizontal distance in the velodyne
  // frame, m); stereo depth error grows with z^2. 0 = keep all.
  double stereo_max_distance_m = 50.0;
  // Both inputs: drop, at load time, the points outside the model's BEV grid (x, y and z ranges):
  // Pillarize would drop them anyway, and a stereo cloud is large (a training holds every frame
  // in memory). Detection is unchanged by it; a training's global rotation can no longer bring
  // points from beyond the grid's edges into its corners (as the camera-view cut already does).
  bool crop_to_grid = true;
  void Check() const;
};

// One frame: points in the velodyne frame and its boxes (labels of the model's classes).
struct Det3dFrame {
  std::string id;
  std::vector<VeloPoint> points;
  std::vector<LidarBox> boxes;  // label = index into the classes
  Calibration calib;
  int image_width = 0, image_height = 0;
};

// The points file of a frame: DATA/SUBSET/velodyne/ID.bin for LiDAR, POINTS/velodyne/ID.bin for
// stereo (the `stereo --encode points` output folder).
std::filesystem::path PointsPath(const KittiDataset& dataset,
                                 const std::filesystem::path& stereo_points_dir, PointSource source,
                                 const std::string& id);

// The points of a scan that a model sees (PointFilterOptions), in their order: finite ones, in the
// grid (crop_to_grid), for stereo within stereo_max_distance_m, for LiDAR in the left camera's
// view of an image_width x image_height image (camera_fov_only).
std::vector<VeloPoint> FilterDet3dPoints(const std::vector<VeloPoint>& raw,
                                         const Calibration& calib, int image_width,
                                         int image_height, PointSource source,
                                         const BevGridOptions& grid,
                                         const PointFilterOptions& filter);

// Reads a frame: calibration, image size (image_2 header), points filtered by `filter` (non-finite
// points always dropped; stereo truncated by distance; LiDAR cut to the camera's view; both cut to
// `grid` with crop_to_grid), and, with `with_labels`, the boxes of `classes` (others, DontCare
// included, ignored).
Det3dFrame LoadDet3dFrame(const KittiDataset& dataset,
                          const std::filesystem::path& stereo_points_dir, PointSource source,
                          const std::string& id, const std::vector<std::string>& classes,
                          const BevGridOptions& grid, const PointFilterOptions& filter,
                          bool with_labels);

// Training augmentation, each step seeded so that a frame's augmentation depends only on (seed,
// epoch, frame).
struct Det3dAugmentOptions {
  bool flip = true;                       // mirror y with probability 1/2
  double global_rotation_rad = M_PI / 8;  // uniform in [-r, r] about z
  double global_scale_min = 0.95, global_scale_max = 1.05;
  // Per object: translation ~ N(0, sigma) in x and y, rotation uniform in [-r, r]; a moved box that
  // overlaps another (BEV IoU > 0) is put back (collision test).
  double object_translation_sigma_m = 0.25;
  double object_rotation_rad = M_PI / 20;
  bool enabled = true;
  void Check() const;
};

// The augmented copy of `frame` (points inside a moved object move with it).
Det3dFrame AugmentFrame(const Det3dFrame& frame, const Det3dAugmentOptions& options, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_DATA_H_
