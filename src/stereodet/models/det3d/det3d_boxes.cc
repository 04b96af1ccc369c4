#include "stereodet/models/det3d/det3d_boxes.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>

#include "stereodet/geometry/iou.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

LidarBox LidarBoxFromObject(const Object& object, const Calibration& calib) {
  const Box3D& b = object.box3d;
  const Eigen::Affine3d velo_from_rect = calib.VeloFromRect();
  const Eigen::Vector3d centre = velo_from_rect * b.Centre();
  // The heading in rect is (cos ry, 0, -sin ry) (geometry/box.cc: the length runs along x').
  const Eigen::Vector3d heading =
      velo_from_rect.linear() *
      Eigen::Vector3d(std::cos(b.rotation_y), 0.0, -std::sin(b.rotation_y));
  LidarBox box;
  box.x = centre.x();
  box.y = centre.y();
  box.z = centre.z();
  box.l = b.l;
  box.w = b.w;
  box.h = b.h;
  box.yaw = std::atan2(heading.y(), heading.x());
  box.label = -1;
  return box;
}

Box3D Box3DFromLidarBox(const LidarBox& box, const Calibration& calib) {
  const Eigen::Affine3d rect_from_velo = calib.RectFromVelo();
  const Eigen::Vector3d centre = rect_from_velo * Eigen::Vector3d(box.x, box.y, box.z);
  const Eigen::Vector3d heading =
      rect_from_velo.linear() * Eigen::Vector3d(std::cos(box.yaw), std::sin(box.yaw), 0.0);
  Box3D b;
  b.h = box.h;
  b.w = box.w;
  b.l = box.l;
  b.location = centre + Eigen::Vector3d(0.0, box.h / 2.0, 0.0);
  b.rotation_y = WrapAngle(std::atan2(-heading.z(), heading.x()));
  return b;
}

Box3D BevProxy(const LidarBox& box) {
  Box3D b;
  b.h = box.h;
  b.w = box.w;
  b.l = box.l;
  b.location = Eigen::Vector3d(-box.y, 0.0, box.x);
  b.rotation_y = -box.yaw - M_PI / 2.0;
  return b;
}

double LidarBevIou(const LidarBox& a, const LidarBox& b) {
  // Far apart: no polygon clipping (most anchor-box pairs).
  const double ra = 0.5 * std::hypot(a.l, a.w), rb = 0.5 * std::hypot(b.l, b.w);
  if (std::hypot(a.x - b.x, a.y - b.y) > ra + rb) return 0.0;
  return BevIou(BevProxy(a), BevProxy(b));
}

std::array<Eigen::Vector2d, 4> LidarBevCorners(const LidarBox& box) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  const double hl = box.l / 2, hw = box.w / 2;
  const double u[4] = {hl, -hl, -hl, hl}, v[4] = {hw, hw, -hw, -hw};
  std::array<Eigen::Vector2d, 4> corners;
  for (int i = 0; i < 4; ++i) {
    corners[i] = {box.x + c * u[i] - s * v[i], box.y + s * u[i] + c * v[i]};
  }
  return corners;
}

Eigen::Vector3d PointInBoxFrame(const LidarBox& box, double x, double y, double z) {
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  const double dx = x - box.x, dy = y - box.y;
  return {c * dx + s * dy, -s * dx + c * dy, z - box.z};
}

bool PointInBox(const LidarBox& box, double x, double y, double z) {
  const Eigen::Vector3d p = PointInBoxFrame(box, x, y, z);
  return std::abs(p.x()) <= box.l / 2 && std::abs(p.y()) <= box.w / 2 &&
         std::abs(p.z()) <= box.h / 2;
}

void RotatedNmsOptions::Check() const {
  STEREODET_CHECK(iou_threshold >= 0.0 && iou_threshold <= 1.0)
      << "NMS IoU threshold must be in [0, 1], got " << iou_threshold;
  STEREODET_CHECK(std::isfinite(score_threshold))
      << "score threshold must be finite, got " << score_threshold;
  STEREODET_CHECK(max_candidates >= 0) << "max_candidates must be >= 0, got " << max_candidates;
  STEREODET_CHECK(max_detections >= 0) << "max_detections must be >= 0, got " << max_detections;
}

std::vector<ScoredLidarBox> RotatedNms(const std::vector<ScoredLidarBox>& boxes,
                                       const RotatedNmsOptions& options) {
  options.Check();
  std::vector<size_t> order;
  for (size_t i = 0; i < boxes.size(); ++i) {
    if (boxes[i].score >= options.score_threshold) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return boxes[a].score > boxes[b].score; });
  if (options.max_candidates > 0 && order.size() > static_cast<size_t>(options.max_candidates)) {
    order.resize(options.max_candidates);
  }
  std::vector<ScoredLidarBox> kept;
  for (size_t i : order) {
    if (options.max_detections > 0 && kept.size() >= static_cast<size_t>(options.max_detections)) {
      break;
    }
    bool suppressed = false;
    for (const ScoredLidarBox& k : kept) {
      if (k.box.label == boxes[i].box.label &&
          LidarBevIou(k.box, boxes[i].box) > options.iou_threshold) {
        suppressed = true;
        break;
      }
    }
    if (!suppressed) kept.push_back(boxes[i]);
  }
  return kept;
}

std::optional<Object> ToKitti3DDetection(const ScoredLidarBox& box,
                                         const std::vector<std::string>& classes,
                                         const Calibration& calib, int image_width,
                                         int image_height) {
  STEREODET_CHECK(box.box.label >= 0 && box.box.label < static_cast<int>(classes.size()))
      << "detection label " << box.box.label << " out of range";
  Object o;
  o.type = classes[box.box.label];
  o.truncated = -1.0;
  o.occluded = -1;
  o.box3d = Box3DFromLidarBox(box.box, calib);
  const Eigen::Matrix<double, 3, 8> corners = Corners(o.box3d);
  double left = 1e18, top = 1e18, right = -1e18, bottom = -1e18;
  for (int i = 0; i < 8; ++i) {
    double depth = 0;
    const Eigen::Vector2d px = calib.ProjectRectToImage(corners.col(i), 2, &depth);
    if (depth <= 0.1) return std::nullopt;
    left = std::min(left, px.x());
    right = std::max(right, px.x());
    top = std::min(top, px.y());
    bottom = std::max(bottom, px.y());
  }
  auto clip = [](double v, double hi) {
    return std::round(std::clamp(v, 0.0, hi) * 100.0) / 100.0;
  };
  o.box = {clip(left, image_width), clip(top, image_height), clip(right, image_width),
           clip(bottom, image_height)};
  if (o.box.Width() <= 0.0 || o.box.Height() <= 0.0) return std::nullopt;
  // Files keep 0.01 m / 0.01 rad precision at most where it reads back exactly; round here so
  // the written file and the returned object agree.
  auto r = [](double v) { return std::round(v * 1e4) / 1e4; };
  o.box3d.h = r(o.box3d.h);
  o.box3d.w = r(o.box3d.w);
  o.box3d.l = r(o.box3d.l);
  o.box3d.location = {r(o.box3d.location.x()), r(o.box3d.location.y()), r(o.box3d.location.z())};
  o.box3d.rotation_y = r(o.box3d.rotation_y);
  o.alpha = r(AlphaFromRotationY(o.box3d.rotation_y, o.box3d.location));
  o.score = std::round(std::clamp(static_cast<double>(box.score), 0.0, 1.0) * 1e6) / 1e6;
  return o;
}

std::pair<int, int> PngImageSize(const std::filesystem::path& path) {
  const std::string head = ReadFileHead(path, 24);  // refuses a FIFO instead of blocking on it
  unsigned char header[24] = {};
  std::copy(head.begin(), head.end(), header);
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  STEREODET_CHECK_IO(head.size() == 24 && std::equal(kSignature, kSignature + 8, header) &&
                     std::equal(header + 12, header + 16, "IHDR"))
      << path.string() << " is not a PNG file";
  auto be32 = [&](int at) {
    return (int64_t{header[at]} << 24) | (int64_t{header[at + 1]} << 16) |
           (int64_t{header[at + 2]} << 8) | int64_t{header[at + 3]};
  };
  const int64_t width = be32(16), height = be32(20);
  STEREODET_CHECK_IO(width > 0 && height > 0 && width < (1 << 20) && height < (1 << 20))
      << path.string() << ": implausible PNG size " << width << "x" << height;
  return {static_cast<int>(width), static_cast<int>(height)};
}

}  // namespace stereodet
