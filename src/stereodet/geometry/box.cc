#include "stereodet/geometry/box.h"

#include <algorithm>
#include <cmath>

namespace stereodet {

double Box2D::Area() const { return std::max(0.0, Width()) * std::max(0.0, Height()); }

Eigen::Matrix<double, 3, 8> Corners(const Box3D& box) {
  // Object frame: x along the length, z along the width, y down (the box spans y in [-h, 0]).
  const double hl = box.l / 2.0, hw = box.w / 2.0;
  const double xs[8] = {hl, hl, -hl, -hl, hl, hl, -hl, -hl};
  const double ys[8] = {0, 0, 0, 0, -box.h, -box.h, -box.h, -box.h};
  const double zs[8] = {hw, -hw, -hw, hw, hw, -hw, -hw, hw};
  // Rotation about y by rotation_y: x' = c x + s z, z' = -s x + c z.
  const double c = std::cos(box.rotation_y), s = std::sin(box.rotation_y);
  Eigen::Matrix<double, 3, 8> corners;
  for (int i = 0; i < 8; ++i) {
    corners(0, i) = c * xs[i] + s * zs[i] + box.location.x();
    corners(1, i) = ys[i] + box.location.y();
    corners(2, i) = -s * xs[i] + c * zs[i] + box.location.z();
  }
  return corners;
}

std::array<BevPoint, 4> BevCorners(const Box3D& box) {
  const Eigen::Matrix<double, 3, 8> corners = Corners(box);
  std::array<BevPoint, 4> bev;
  for (int i = 0; i < 4; ++i) bev[i] = BevPoint(corners(0, i), corners(2, i));
  return bev;
}

}  // namespace stereodet
