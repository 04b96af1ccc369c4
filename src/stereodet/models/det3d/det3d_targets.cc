#include "stereodet/models/det3d/det3d_targets.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

int Cells(double lo, double hi, double size) {
  return static_cast<int>(std::lround((hi - lo) / size));
}

}  // namespace

void BevGridOptions::Check() const {
  STEREODET_CHECK(pillar_m > 0.0 && std::isfinite(pillar_m))
      << "pillar size must be > 0, got " << pillar_m;
  STEREODET_CHECK(max_x_m > min_x_m && max_y_m > min_y_m && max_z_m > min_z_m)
      << "empty BEV range x [" << min_x_m << ", " << max_x_m << "] y [" << min_y_m << ", "
      << max_y_m << "] z [" << min_z_m << ", " << max_z_m << "]";
  const double rows = (max_x_m - min_x_m) / pillar_m, cols = (max_y_m - min_y_m) / pillar_m;
  STEREODET_CHECK(std::abs(rows - std::round(rows)) < 1e-6 &&
                  std::abs(cols - std::round(cols)) < 1e-6)
      << "the BEV range must be a whole number of pillars, got " << rows << " x " << cols;
  STEREODET_CHECK(Rows() % 8 == 0 && Cols() % 8 == 0 && Rows() <= 2048 && Cols() <= 2048)
      << "the BEV canvas must be a multiple of 8 cells each way (at most 2048), got " << Rows()
      << " x " << Cols();
}

int BevGridOptions::Rows() const { return Cells(min_x_m, max_x_m, pillar_m); }
int BevGridOptions::Cols() const { return Cells(min_y_m, max_y_m, pillar_m); }

bool BevGridOptions::Contains(double x, double y, double z) const {
  return x >= min_x_m && x < max_x_m && y >= min_y_m && y < max_y_m && z >= min_z_m && z <= max_z_m;
}

Pillars Pillarize(const std::vector<VeloPoint>& points, const BevGridOptions& grid) {
  grid.Check();
  const int rows = grid.Rows(), cols = grid.Cols();
  Pillars out;
  std::vector<const VeloPoint*> kept;
  for (const VeloPoint& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
    if (!grid.Contains(p.x, p.y, p.z)) continue;
    const int row = std::min(rows - 1, static_cast<int>((p.x - grid.min_x_m) / grid.pillar_m));
    const int col = std::min(cols - 1, static_cast<int>((p.y - grid.min_y_m) / grid.pillar_m));
    out.cell.push_back(static_cast<int64_t>(row) * cols + col);
    kept.push_back(&p);
  }
  // Pillar means.
  std::unordered_map<int64_t, std::array<double, 4>> sums;  // x, y, z, count
  for (size_t i = 0; i < kept.size(); ++i) {
    std::array<double, 4>& s = sums[out.cell[i]];
    s[0] += kept[i]->x;
    s[1] += kept[i]->y;
    s[2] += kept[i]->z;
    s[3] += 1;
  }
  out.num_pillars = static_cast<int>(sums.size());
  out.features.resize(kept.size() * kPillarFeatures);
  out.xyz.resize(kept.size() * 3);
  for (size_t i = 0; i < kept.size(); ++i) {
    const VeloPoint& p = *kept[i];
    const std::array<double, 4>& s = sums[out.cell[i]];
    const int64_t row = out.cell[i] / cols, col = out.cell[i] % cols;
    const double cx = grid.min_x_m + (row + 0.5) * grid.pillar_m;
    const double cy = grid.min_y_m + (col + 0.5) * grid.pillar_m;
    float* f = &out.features[i * kPillarFeatures];
    f[0] = p.x;
    f[1] = p.y;
    f[2] = p.z;
    f[3] = p.reflectance;
    f[4] = static_cast<float>(p.x - s[0] / s[3]);
    f[5] = static_cast<float>(p.y - s[1] / s[3]);
    f[6] = static_cast<float>(p.z - s[2] / s[3]);
    f[7] = static_cast<float>(p.x - cx);
    f[8] = static_cast<float>(p.y - cy);
    out.xyz[i * 3] = p.x;
    out.xyz[i * 3 + 1] = p.y;
    out.xyz[i * 3 + 2] = p.z;
  }
  return out;
}

AnchorClass DefaultAnchorClass(const std::string& name) {
  AnchorClass a;
  if (name == "Pedestrian") {
    a = {.l = 0.8, .w = 0.6, .h = 1.73, .z = -0.6, .positive_iou = 0.5, .negative_iou = 0.35};
  } else if (name == "Cyclist") {
    a = {.l = 1.76, .w = 0.6, .h = 1.73, .z = -0.6, .positive_iou = 0.5, .negative_iou = 0.35};
  } else if (name == "Van") {
    a = {.l = 5.1, .w = 1.9, .h = 2.1, .z = -0.8, .positive_iou = 0.6, .negative_iou = 0.45};
  }
  return a;
}

std::vector<LidarBox> GenerateAnchors(const BevGridOptions& grid, int stride,
                                      const std::vector<AnchorClass>& classes) {
  grid.Check();
  STEREODET_CHECK(stride >= 1 && grid.Rows() % stride == 0 && grid.Cols() % stride == 0)
      << "anchor stride " << stride << " does not divide the canvas";
  const int rows = grid.Rows() / stride, cols = grid.Cols() / stride;
  const double cell = grid.pillar_m * stride;
  std::vector<LidarBox> anchors;
  anchors.reserve(static_cast<size_t>(rows) * cols * classes.size() * kAnchorRotations);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      for (size_t k = 0; k < classes.size(); ++k) {
        for (int rot = 0; rot < kAnchorRotations; ++rot) {
          const AnchorClass& a = classes[k];
          anchors.push_back({.x = grid.min_x_m + (r + 0.5) * cell,
                             .y = grid.min_y_m + (c + 0.5) * cell,
                             .z = a.z,
                             .l = a.l,
                             .w = a.w,
                             .h = a.h,
                             .yaw = rot * M_PI / 2.0,
                             .label = static_cast<int>(k)});
        }
      }
    }
  }
  return anchors;
}

std::array<float, kBoxCodeSize> EncodeBox(const LidarBox& box, const LidarBox& anchor) {
  const double d = std::hypot(anchor.l, anchor.w);
  return {static_cast<float>((box.x - anchor.x) / d),
          static_cast<float>((box.y - anchor.y) / d),
          static_cast<float>((box.z - anchor.z) / anchor.h),
          static_cast<float>(std::log(box.l / anchor.l)),
          static_cast<float>(std::log(box.w / anchor.w)),
          static_cast<float>(std::log(box.h / anchor.h)),
          static_cast<float>(box.yaw - anchor.yaw)};
}

LidarBox DecodeBox(const std::array<float, kBoxCodeSize>& code, const LidarBox& anchor) {
  const double d = std::hypot(anchor.l, anchor.w);
  // Size residuals are clamped so that an untrained head cannot overflow exp().
  auto size = [](double residual) { return std::exp(std::clamp(residual, -4.0, 4.0)); };
  LidarBox box;
  box.x = anchor.x + code[0] * d;
  box.y = anchor.y + code[1] * d;
  box.z = anchor.z + code[2] * anchor.h;
  box.l = anchor.l * size(code[3]);
  box.w = anchor.w * size(code[4]);
  box.h = anchor.h * size(code[5]);
  box.yaw = anchor.yaw + code[6];
  box.label = anchor.label;
  return box;
}

int DirectionBin(double yaw) {
  double m = std::fmod(yaw, 2.0 * M_PI);
  if (m < 0) m += 2.0 * M_PI;
  return m < M_PI ? 0 : 1;
}

double ApplyDirection(double yaw, int direction_bin) {
  double m = std::fmod(yaw, M_PI);
  if (m < 0) m += M_PI;
  return WrapAngle(m + (direction_bin == 1 ? M_PI : 0.0));
}

AnchorTargets AssignAnchors(const std::vector<LidarBox>& anchors,
                            const std::vector<int>& anchor_class,
                            const std::vector<AnchorClass>& classes,
                            const std::vector<LidarBox>& boxes) {
  STEREODET_CHECK(anchor_class.size() == anchors.size())
      << "anchor_class has " << anchor_class.size() << " entries for " << anchors.size()
      << " anchors";
  const size_t n = anchors.size();
  AnchorTargets t;
  t.labels.assign(n, 0);
  t.box_codes.assign(n * kBoxCodeSize, 0.0f);
  t.directions.assign(n, 0);
  std::vector<double> best_iou(n, 0.0);
  std::vector<int> best_box(n, -1);
  std::vector<int> forced(n, -1);  // the box whose best anchor this is
  for (size_t b = 0; b < boxes.size(); ++b) {
    const LidarBox& box = boxes[b];
    if (box.label < 0 || box.label >= static_cast<int>(classes.size())) continue;
    double box_best = 0.0;
    int64_t box_best_anchor = -1;
    const double reach = 0.5 * std::hypot(box.l, box.w);
    for (size_t i = 0; i < n; ++i) {
      if (anchor_class[i] != box.label) continue;
      const LidarBox& a = anchors[i];
      if (std::abs(a.x - box.x) > reach + 0.5 * std::hypot(a.l, a.w) ||
          std::abs(a.y - box.y) > reach + 0.5 * std::hypot(a.l, a.w)) {
        continue;
      }
      const double iou = LidarBevIou(a, box);
      if (iou > best_iou[i]) {
        best_iou[i] = iou;
        best_box[i] = static_cast<int>(b);
      }
      if (iou > box_best) {
        box_best = iou;
        box_best_anchor = static_cast<int64_t>(i);
      }
    }
    if (box_best_anchor >= 0) forced[box_best_anchor] = static_cast<int>(b);
  }
  for (size_t i = 0; i < n; ++i) {
    const AnchorClass& cls = classes[anchor_class[i]];
    int matched = -1;
    if (forced[i] >= 0) {
      matched = forced[i];
    } else if (best_box[i] >= 0 && best_iou[i] >= cls.positive_iou) {
      matched = best_box[i];
    } else if (best_iou[i] >= cls.negative_iou) {
      t.labels[i] = kIgnoreAnchor;
    }
    if (matched < 0) continue;
    t.labels[i] = boxes[matched].label + 1;
    const std::array<float, kBoxCodeSize> code = EncodeBox(boxes[matched], anchors[i]);
    std::copy(code.begin(), code.end(), t.box_codes.begin() + i * kBoxCodeSize);
    t.directions[i] = DirectionBin(boxes[matched].yaw);
    ++t.num_positive;
  }
  return t;
}

PointTargets AuxiliaryTargets(const std::vector<float>& xyz, const std::vector<LidarBox>& boxes) {
  STEREODET_CHECK(xyz.size() % 3 == 0) << "xyz must hold 3 floats a point, got " << xyz.size();
  const size_t n = xyz.size() / 3;
  PointTargets t;
  t.foreground.assign(n, 0.0f);
  t.offsets.assign(n * 3, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    const double x = xyz[3 * i], y = xyz[3 * i + 1], z = xyz[3 * i + 2];
    for (const LidarBox& box : boxes) {
      if (!PointInBox(box, x, y, z)) continue;
      t.foreground[i] = 1.0f;
      t.offsets[3 * i] = static_cast<float>(box.x - x);
      t.offsets[3 * i + 1] = static_cast<float>(box.y - y);
      t.offsets[3 * i + 2] = static_cast<float>(box.z - z);
      ++t.num_foreground;
      break;
    }
  }
  return t;
}

std::vector<std::array<double, 2>> PartSamplingPoints(const LidarBox& box, int parts_l,
                                                      int parts_w) {
  STEREODET_CHECK(parts_l >= 1 && parts_w >= 1)
      << "part grid must be at least 1 x 1, got " << parts_l << " x " << parts_w;
  const double c = std::cos(box.yaw), s = std::sin(box.yaw);
  std::vector<std::array<double, 2>> points;
  for (int i = 0; i < parts_l; ++i) {
    for (int j = 0; j < parts_w; ++j) {
      const double u = ((i + 0.5) / parts_l - 0.5) * box.l;
      const double v = ((j + 0.5) / parts_w - 0.5) * box.w;
      points.push_back({box.x + c * u - s * v, box.y + s * u + c * v});
    }
  }
  return points;
}

std::array<double, 2> NormalizedBevCoordinates(double x, double y, const BevGridOptions& grid) {
  return {2.0 * (y - grid.min_y_m) / (grid.max_y_m - grid.min_y_m) - 1.0,
          2.0 * (x - grid.min_x_m) / (grid.max_x_m - grid.min_x_m) - 1.0};
}

}  // namespace stereodet
