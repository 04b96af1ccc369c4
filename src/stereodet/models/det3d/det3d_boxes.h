// Boxes of the single-stage 3D detector (issue 14), torch-free: 3D boxes in the velodyne frame,
// their conversion to and from KITTI's camera-frame labels through a frame's calibration, BEV IoU
// (the geometry module's rotated IoU), points inside a rotated box, rotated NMS in BEV and the
// KITTI-format detection of a box.
#ifndef STEREODET_MODELS_DET3D_DET3D_BOXES_H_
#define STEREODET_MODELS_DET3D_DET3D_BOXES_H_

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/geometry/box.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"
#include "stereodet/kitti/velodyne_io.h"

namespace stereodet {

// A 3D box in the velodyne frame (x forward, y left, z up), metres and radians.
struct LidarBox {
  double x = 0, y = 0, z = 0;  // the box's centre (not its bottom face)
  double l = 0, w = 0, h = 0;  // length along the heading, width, height
  double yaw = 0;              // heading about +z, from +x towards +y
  int label = 0;               // class index (0-based into the model's classes)
  bool operator==(const LidarBox&) const = default;
};

// A box with a score, as the detector emits it.
struct ScoredLidarBox {
  LidarBox box;
  float score = 0;  // [0, 1]
};

// KITTI label (rect frame, bottom centre, rotation_y) -> velodyne box, exact through `calib`
// (the heading is the label's direction mapped through VeloFromRect). label = -1 (set by caller).
LidarBox LidarBoxFromObject(const Object& object, const Calibration& calib);
// The inverse: a camera-frame Box3D (bottom centre, rotation_y) of a velodyne box.
Box3D Box3DFromLidarBox(const LidarBox& box, const Calibration& calib);

// The box's footprint as a camera-frame-like Box3D for the geometry module's BEV IoU (BEV x = -y,
// z = x, rotation_y = -yaw - pi/2): same footprint, so BevIou of two of them is the BEV IoU in the
// velodyne frame.
Box3D BevProxy(const LidarBox& box);
double LidarBevIou(const LidarBox& a, const LidarBox& b);

// The four BEV corners (x, y) in the velodyne frame, counter-clockwise from front-left.
std::array<Eigen::Vector2d, 4> LidarBevCorners(const LidarBox& box);

// True when the point lies inside the box (boundary included), in 3D.
bool PointInBox(const LidarBox& box, double x, double y, double z);
// The point in the box's own frame: (along the length, along the width, up), centre at 0.
Eigen::Vector3d PointInBoxFrame(const LidarBox& box, double x, double y, double z);

struct RotatedNmsOptions {
  // A box is suppressed by a higher-scored kept box of the same label whose BEV IoU with it is
  // strictly greater than this.
  double iou_threshold = 0.1;
  float score_threshold = 0.0f;  // boxes scoring below are dropped first
  int max_candidates = 1000;     // only the best this many enter NMS (0 = all)
  int max_detections = 100;      // at most this many are kept (0 = all)
  void Check() const;            // throws std::invalid_argument
};

// Greedy NMS in BEV over all labels (a box suppresses only boxes of its own label): visited from
// the highest score down (ties: input order). Returns the kept boxes, best first.
std::vector<ScoredLidarBox> RotatedNms(const std::vector<ScoredLidarBox>& boxes,
                                       const RotatedNmsOptions& options);

// A KITTI detection of a velodyne box: type = classes[label], dimensions, location (bottom
// centre, rect), rotation_y and alpha (wrapped to [-pi, pi)), the 2D box the projected 8 corners
// span in camera 2, clipped to the image; score kept (rounded to 1e-6), truncated/occluded -1.
// Returns nothing when a corner lies behind the camera or the projection misses the image.
std::optional<Object> ToKitti3DDetection(const ScoredLidarBox& box,
                                         const std::vector<std::string>& classes,
                                         const Calibration& calib, int image_width,
                                         int image_height);

// Width and height of a PNG file from its header (no decoding). Throws std::runtime_error naming
// the file when it is not a PNG.
std::pair<int, int> PngImageSize(const std::filesystem::path& path);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_BOXES_H_
