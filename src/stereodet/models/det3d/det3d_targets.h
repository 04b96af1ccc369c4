// The single-stage 3D detector's data side, torch-free (issue 14): the BEV grid and its pillars,
// anchors and their assignment to ground truth, the box coding (SECOND's residuals, yaw with a
// direction bin), the auxiliary network's point targets (SA-SSD: foreground and centre offsets),
// and the part-sensitive sampling points of PSWarp.
#ifndef STEREODET_MODELS_DET3D_DET3D_TARGETS_H_
#define STEREODET_MODELS_DET3D_DET3D_TARGETS_H_

#include <array>
#include <cstdint>
#include <vector>

#include "stereodet/models/det3d/det3d_boxes.h"

namespace stereodet {

// The BEV canvas, velodyne frame: rows along x (forward), columns along y (left), each cell a
// pillar of pillar_m x pillar_m spanning [min_z_m, max_z_m].
struct BevGridOptions {
  double min_x_m = 0.0, max_x_m = 48.0;
  double min_y_m = -24.0, max_y_m = 24.0;
  double min_z_m = -3.0, max_z_m = 1.0;
  double pillar_m = 0.4;
  void Check() const;  // throws std::invalid_argument: empty ranges, rows/columns not a multiple
                       // of 8 (the backbone's strides)
  int Rows() const;    // (max_x - min_x) / pillar
  int Cols() const;    // (max_y - min_y) / pillar
  bool Contains(double x, double y, double z) const;  // half-open in x, y; closed in z
};

// Number of decorated features per point (below).
inline constexpr int kPillarFeatures = 9;

// Points grouped into pillars, PointPillars' decoration: per point in the grid (others dropped),
// the cell it falls into (row * Cols() + col) and 9 features
//   x, y, z, reflectance, x - mean_x, y - mean_y, z - mean_z (its pillar's mean),
//   x - cell_centre_x, y - cell_centre_y.
struct Pillars {
  std::vector<int64_t> cell;    // per kept point
  std::vector<float> features;  // [kept point][kPillarFeatures]
  std::vector<float> xyz;       // [kept point][3], the raw coordinates (auxiliary network)
  int num_pillars = 0;          // distinct cells
};
Pillars Pillarize(const std::vector<VeloPoint>& points, const BevGridOptions& grid);

// One anchor class: box size and centre height in the velodyne frame, the IoU thresholds of its
// assignment.
struct AnchorClass {
  double l = 3.9, w = 1.6, h = 1.56;  // Car (SECOND / PointPillars)
  double z = -1.0;                    // centre height, m (velodyne frame)
  double positive_iou = 0.6, negative_iou = 0.45;
};
// The default anchor class of a KITTI class name (Car, Pedestrian, Cyclist, Van; others get Car's
// sizes).
AnchorClass DefaultAnchorClass(const std::string& name);

// Anchors on the head's map (stride `stride` cells of the canvas): at every cell centre, for each
// class c, for each yaw in {0, pi/2}: index ((row * cols + col) * classes + c) * 2 + r.
std::vector<LidarBox> GenerateAnchors(const BevGridOptions& grid, int stride,
                                      const std::vector<AnchorClass>& classes);
inline constexpr int kAnchorRotations = 2;

// Box coding (SECOND): with d = sqrt(l_a^2 + w_a^2), the residuals
// (dx/d, dy/d, dz/h_a, log(l/l_a), log(w/w_a), log(h/h_a), yaw - yaw_a)
inline constexpr int kBoxCodeSize = 7;
std::array<float, kBoxCodeSize> EncodeBox(const LidarBox& box, const LidarBox& anchor);
// The inverse; the yaw is anchor yaw + residual, unwrapped (no direction applied).
LidarBox DecodeBox(const std::array<float, kBoxCodeSize>& code, const LidarBox& anchor);
// Direction bin of a yaw: 0 when yaw mod 2 pi is in [0, pi), else 1.
int DirectionBin(double yaw);
// A decoded yaw put into the half turn of `direction_bin`: yaw mod pi, plus pi for bin 1, wrapped
// to [-pi, pi).
double ApplyDirection(double yaw, int direction_bin);

// Per-anchor targets of one frame.
inline constexpr int kIgnoreAnchor = -1;
struct AnchorTargets {
  std::vector<int> labels;          // per anchor: -1 ignore, 0 background, 1 + class index
  std::vector<float> box_codes;     // [anchor][kBoxCodeSize]; 0 for non-positives
  std::vector<int64_t> directions;  // per anchor: DirectionBin of the matched box (0 else)
  int num_positive = 0;
};
// Assignment: an anchor is positive for a box of its class with BEV IoU >= positive_iou, or when
// it is that box's best anchor (IoU > 0); negative when its best IoU with any box of its class is
// < negative_iou; ignored between. `anchor_class[i]` is anchor i's class index. Boxes with labels
// outside the classes are skipped.
AnchorTargets AssignAnchors(const std::vector<LidarBox>& anchors,
                            const std::vector<int>& anchor_class,
                            const std::vector<AnchorClass>& classes,
                            const std::vector<LidarBox>& boxes);

// SA-SSD's auxiliary targets per point (xyz as in Pillars::xyz): foreground when inside a box,
// and then the offset from the point to that box's centre (box - point, metres); 0 else.
struct PointTargets {
  std::vector<float> foreground;  // per point, 0 or 1
  std::vector<float> offsets;     // [point][3]
  int num_foreground = 0;
};
PointTargets AuxiliaryTargets(const std::vector<float>& xyz, const std::vector<LidarBox>& boxes);

// PSWarp's sampling points: the centres of a parts_l x parts_w grid of parts over the box's
// footprint, part k = i * parts_w + j at (((i + 0.5) / parts_l - 0.5) l, ((j + 0.5) / parts_w -
// 0.5) w) in the box frame, rotated by yaw about the centre: [part][x, y] in metres.
std::vector<std::array<double, 2>> PartSamplingPoints(const LidarBox& box, int parts_l,
                                                      int parts_w);
// A velodyne (x, y) as grid_sample's normalized coordinates over the canvas (align_corners
// false): (u along columns = y, v along rows = x), -1 and 1 at the canvas edges.
std::array<double, 2> NormalizedBevCoordinates(double x, double y, const BevGridOptions& grid);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_TARGETS_H_
