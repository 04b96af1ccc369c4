#include "stereodet/geometry/box.h"

#include <gtest/gtest.h>

#include <cmath>

namespace stereodet {
namespace {

TEST(Box2DTest, SizesAndArea) {
  const Box2D box{10, 20, 50, 100};
  EXPECT_EQ(box.Width(), 40);
  EXPECT_EQ(box.Height(), 80);
  EXPECT_EQ(box.Area(), 3200);
  EXPECT_EQ((Box2D{10, 20, 5, 100}).Area(), 0);  // inverted: no negative area
}

TEST(Box3DTest, CornersOfAnUnrotatedBox) {
  Box3D box;
  box.h = 1.5;
  box.w = 2.0;
  box.l = 4.0;
  box.location = {1.0, 1.65, 10.0};
  const auto corners = Corners(box);
  // Bottom face at y = 1.65, top face at y = 0.15; length along x, width along z.
  EXPECT_DOUBLE_EQ(corners(0, 0), 3.0);
  EXPECT_DOUBLE_EQ(corners(2, 0), 11.0);
  EXPECT_DOUBLE_EQ(corners(1, 0), 1.65);
  EXPECT_DOUBLE_EQ(corners(0, 2), -1.0);
  EXPECT_DOUBLE_EQ(corners(2, 2), 9.0);
  EXPECT_DOUBLE_EQ(corners(1, 4), 0.15);
  EXPECT_DOUBLE_EQ(box.Volume(), 12.0);
  EXPECT_DOUBLE_EQ(box.Centre().y(), 0.9);
}

TEST(Box3DTest, RotationByNinetyDegreesTurnsLengthOntoZ) {
  Box3D box;
  box.h = 1;
  box.w = 2;
  box.l = 4;
  box.rotation_y = M_PI / 2;
  const auto bev = BevCorners(box);
  // Object +x (length) maps to camera -z for rotation_y = +90 degrees: x' = c x + s z, z' = -s x +
  // c z.
  EXPECT_NEAR(bev[0].x(), 1.0, 1e-12);  // (l/2, w/2) -> (w/2, -l/2)
  EXPECT_NEAR(bev[0].y(), -2.0, 1e-12);
  double min_z = 1e9, max_z = -1e9;
  for (const auto& p : bev) {
    min_z = std::min(min_z, p.y());
    max_z = std::max(max_z, p.y());
  }
  EXPECT_NEAR(max_z - min_z, 4.0, 1e-12);
}

}  // namespace
}  // namespace stereodet
