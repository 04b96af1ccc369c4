#include "stereodet/geometry/iou.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace stereodet {
namespace {

Box3D MakeBox(double x, double z, double l, double w, double ry, double y = 1.5, double h = 1.5) {
  Box3D box;
  box.location = {x, y, z};
  box.l = l;
  box.w = w;
  box.h = h;
  box.rotation_y = ry;
  return box;
}

// --- An independent reference: intersection of two convex polygons as the convex hull of (a) the
// vertices of each inside the other and (b) the crossings of their edges. Shares no code with the
// clipping in iou.cc.
using P = Eigen::Vector2d;

double Cross(const P& o, const P& a, const P& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

bool InsideConvex(const std::array<P, 4>& poly, const P& p) {
  // Works for either orientation: p is inside if it is on the same side of every edge.
  int positive = 0, negative = 0;
  for (int i = 0; i < 4; ++i) {
    const double c = Cross(poly[i], poly[(i + 1) % 4], p);
    positive += c > 1e-12;
    negative += c < -1e-12;
  }
  return positive == 0 || negative == 0;
}

double HullArea(std::vector<P> points) {
  if (points.size() < 3) return 0;
  std::sort(points.begin(), points.end(), [](const P& a, const P& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<P> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {  // Andrew's monotone chain
    while (k >= 2 && Cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && Cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
    hull[k++] = points[i - 1];
  }
  hull.resize(k - 1);
  double twice = 0;
  for (size_t i = 0; i < hull.size(); ++i) {
    twice += hull[i].x() * hull[(i + 1) % hull.size()].y() -
             hull[(i + 1) % hull.size()].x() * hull[i].y();
  }
  return std::abs(twice) / 2;
}

double ReferenceBevIntersection(const Box3D& a, const Box3D& b) {
  const auto pa = BevCorners(a), pb = BevCorners(b);
  std::vector<P> points;
  for (const P& p : pa)
    if (InsideConvex(pb, p)) points.push_back(p);
  for (const P& p : pb)
    if (InsideConvex(pa, p)) points.push_back(p);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const P& p1 = pa[i];
      const P& p2 = pa[(i + 1) % 4];
      const P& q1 = pb[j];
      const P& q2 = pb[(j + 1) % 4];
      const P r = p2 - p1, s = q2 - q1;
      const double denom = r.x() * s.y() - r.y() * s.x();
      if (std::abs(denom) < 1e-15) continue;
      const double t = ((q1 - p1).x() * s.y() - (q1 - p1).y() * s.x()) / denom;
      const double u = ((q1 - p1).x() * r.y() - (q1 - p1).y() * r.x()) / denom;
      if (t >= 0 && t <= 1 && u >= 0 && u <= 1) points.push_back(p1 + t * r);
    }
  }
  return HullArea(points);
}

// A second, cruder reference: the fraction of a dense grid over a's footprint that falls in b.
double SampledBevIntersection(const Box3D& a, const Box3D& b, int n) {
  const auto pb = BevCorners(b);
  const double c = std::cos(a.rotation_y), s = std::sin(a.rotation_y);
  int inside = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double ox = ((i + 0.5) / n - 0.5) * a.l, oz = ((j + 0.5) / n - 0.5) * a.w;
      const P p(c * ox + s * oz + a.location.x(), -s * ox + c * oz + a.location.z());
      inside += InsideConvex(pb, p);
    }
  }
  return a.l * a.w * inside / (static_cast<double>(n) * n);
}

TEST(Iou2DTest, HandComputedCases) {
  const Box2D a{0, 0, 10, 10};
  EXPECT_EQ(Iou2D(a, a), 1.0);
  EXPECT_DOUBLE_EQ(Iou2D(a, Box2D{5, 0, 15, 10}), 50.0 / 150.0);
  EXPECT_EQ(Iou2D(a, Box2D{10, 0, 20, 10}), 0.0);                 // touching
  EXPECT_EQ(Iou2D(Box2D{0, 0, 0, 10}, Box2D{0, 0, 0, 10}), 0.0);  // zero area, no NaN
  // Two boxes of IoU exactly 1/2: a inside b, half its area.
  EXPECT_EQ(Iou2D(Box2D{0, 0, 10, 10}, Box2D{0, 0, 20, 10}), 0.5);
}

TEST(BevIouTest, IdenticalBoxesGiveExactlyOne) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-40, 40), size(0.3, 12), angle(-M_PI, M_PI);
  for (int i = 0; i < 10000; ++i) {
    const Box3D box =
        MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng), pos(rng) / 10, size(rng));
    ASSERT_EQ(BevIou(box, box), 1.0) << i;
    ASSERT_EQ(Iou3D(box, box), 1.0) << i;
  }
}

TEST(BevIouTest, SquareTurnedByMultiplesOfNinetyDegreesGivesOne) {
  const Box3D square = MakeBox(3.7, 12.1, 2.5, 2.5, 0.3);
  for (int k = -4; k <= 4; ++k) {
    Box3D turned = square;
    turned.rotation_y += k * M_PI / 2;
    EXPECT_EQ(BevIou(square, turned), 1.0) << k;
    EXPECT_EQ(Iou3D(square, turned), 1.0) << k;
  }
  // A 4 x 2 rectangle turned by 180 degrees is itself.
  const Box3D car = MakeBox(1, 20, 4, 2, 1.0);
  Box3D flipped = car;
  flipped.rotation_y += M_PI;
  EXPECT_EQ(BevIou(car, flipped), 1.0);
}

TEST(BevIouTest, TouchingAndZeroAreaBoxesGiveZero) {
  EXPECT_EQ(BevIou(MakeBox(0, 0, 2, 2, 0), MakeBox(2, 0, 2, 2, 0)), 0.0);
  EXPECT_EQ(BevIou(MakeBox(0, 0, 2, 2, 0.7), MakeBox(5, 5, 2, 2, 0.7)), 0.0);
  // Rotated boxes touching along a shared edge.
  const double ry = 0.4;
  const Box3D a = MakeBox(0, 0, 2, 2, ry);
  const Box3D b = MakeBox(2 * std::cos(ry), -2 * std::sin(ry), 2, 2, ry);
  EXPECT_NEAR(BevIou(a, b), 0.0, 1e-12);
  const Box3D flat = MakeBox(0, 0, 2, 0, 0.3);
  EXPECT_EQ(BevIou(flat, flat), 0.0);
  EXPECT_EQ(Iou3D(flat, flat), 0.0);
  const Box3D no_height = MakeBox(0, 0, 2, 2, 0.3, 1.5, 0.0);
  EXPECT_EQ(Iou3D(no_height, no_height), 0.0);
}

TEST(BevIouTest, HandComputedCases) {
  // Half-overlapping unit-aligned squares: intersection 2, union 6.
  EXPECT_DOUBLE_EQ(BevIou(MakeBox(0, 0, 2, 2, 0), MakeBox(1, 0, 2, 2, 0)), 2.0 / 6.0);
  // A square and the same square turned by 45 degrees about the same centre: the intersection is a
  // regular octagon of area 8 (sqrt(2) - 1) for side 2.
  const double octagon = 8 * (std::sqrt(2.0) - 1);
  EXPECT_NEAR(BevIntersectionArea(MakeBox(0, 0, 2, 2, 0), MakeBox(0, 0, 2, 2, M_PI / 4)), octagon,
              1e-12);
  EXPECT_NEAR(BevIou(MakeBox(0, 0, 2, 2, 0), MakeBox(0, 0, 2, 2, M_PI / 4)),
              octagon / (8 - octagon), 1e-12);
  // A box containing another: IoU = small area / large area.
  EXPECT_DOUBLE_EQ(BevIou(MakeBox(0, 0, 4, 4, 0.2), MakeBox(0, 0, 2, 2, 0.2)), 0.25);
}

TEST(Iou3DTest, HeightOverlapScalesTheIntersection) {
  // Same footprint, y extents [0, 2] and [1, 3]: intersection 1/2 of each volume, IoU 1/3.
  const Box3D a = MakeBox(0, 10, 4, 2, 0.3, 2.0, 2.0);
  const Box3D b = MakeBox(0, 10, 4, 2, 0.3, 3.0, 2.0);
  EXPECT_NEAR(Iou3D(a, b), 1.0 / 3.0, 1e-12);
  EXPECT_EQ(BevIou(a, b), 1.0);
  const Box3D above = MakeBox(0, 10, 4, 2, 0.3, 0.0, 2.0);  // spans [-2, 0]: touches a at y = 0
  EXPECT_EQ(Iou3D(a, above), 0.0);
}

TEST(BevIouTest, MatchesIndependentPolygonReferenceOnRandomPairs) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> pos(-3, 3), size(0.2, 6), angle(-M_PI, M_PI);
  int overlapping = 0;
  for (int i = 0; i < 20000; ++i) {
    const Box3D a = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng));
    Box3D b = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng));
    if (i % 5 == 0) b.rotation_y = a.rotation_y;  // many axis-aligned-in-a's-frame pairs too
    const double area = BevIntersectionArea(a, b);
    const double reference = ReferenceBevIntersection(a, b);
    ASSERT_NEAR(area, reference, 1e-9 * (1 + reference)) << i;
    ASSERT_NEAR(BevIntersectionArea(b, a), area, 1e-9 * (1 + area)) << i;  // symmetric
    const double iou = BevIou(a, b);
    ASSERT_GE(iou, 0.0);
    ASSERT_LE(iou, 1.0);
    overlapping += area > 0;
  }
  EXPECT_GT(overlapping, 5000);  // the test exercised real overlaps, not just rejections
}

TEST(BevIouTest, MatchesDenseSamplingOnRandomPairs) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(-1.5, 1.5), size(1, 4), angle(-M_PI, M_PI);
  for (int i = 0; i < 300; ++i) {
    const Box3D a = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng));
    const Box3D b = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng));
    const double sampled = SampledBevIntersection(a, b, 400);
    // Grid error is about perimeter x cell size.
    ASSERT_NEAR(BevIntersectionArea(a, b), sampled, 0.02 * std::max(a.l, a.w)) << i;
  }
}

TEST(Iou2DTest, MatchesCellCountingOnRandomIntegerBoxes) {
  // Boxes with integer corners in [0, 12]: the intersection and union are whole unit cells, counted
  // one by one, so the reference is exact and shares nothing with iou.cc's interval arithmetic.
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> coordinate(0, 12);
  auto random_box = [&]() {
    const int x1 = coordinate(rng), x2 = coordinate(rng), y1 = coordinate(rng),
              y2 = coordinate(rng);
    return Box2D{static_cast<double>(std::min(x1, x2)), static_cast<double>(std::min(y1, y2)),
                 static_cast<double>(std::max(x1, x2)), static_cast<double>(std::max(y1, y2))};
  };
  auto inside = [](const Box2D& box, int x, int y) {  // the cell [x, x+1] x [y, y+1]
    return x >= box.left && x + 1 <= box.right && y >= box.top && y + 1 <= box.bottom;
  };
  int overlapping = 0;
  for (int i = 0; i < 3000; ++i) {
    const Box2D a = random_box(), b = random_box();
    int both = 0, either = 0;
    for (int x = 0; x < 12; ++x) {
      for (int y = 0; y < 12; ++y) {
        both += inside(a, x, y) && inside(b, x, y);
        either += inside(a, x, y) || inside(b, x, y);
      }
    }
    ASSERT_EQ(IntersectionArea(a, b), both) << i;
    ASSERT_EQ(IntersectionArea(b, a), both) << i;
    const double expected = either == 0 ? 0.0 : static_cast<double>(both) / either;
    ASSERT_NEAR(Iou2D(a, b), expected, 1e-15) << i;
    overlapping += both > 0;
  }
  EXPECT_GT(overlapping, 500);
}

TEST(Iou3DTest, MatchesIndependentReferenceOnRandomPairs) {
  // The polygon reference for the footprint times a y overlap counted on a fine grid of heights:
  // y extents on a 1/64 m grid, so counting 1/64-m slabs is exact.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-3, 3), size(0.2, 6), angle(-M_PI, M_PI);
  std::uniform_int_distribution<int> slab(0, 160), slabs(1, 160);  // bottom and height, 1/64 m
  int overlapping = 0;
  for (int i = 0; i < 5000; ++i) {
    const int bottom_a = slab(rng), height_a = slabs(rng), bottom_b = slab(rng),
              height_b = slabs(rng);
    // location.y is the bottom face (KITTI: y down), the box spans [y - h, y].
    const Box3D a = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng),
                            (bottom_a + height_a) / 64.0, height_a / 64.0);
    const Box3D b = MakeBox(pos(rng), pos(rng), size(rng), size(rng), angle(rng),
                            (bottom_b + height_b) / 64.0, height_b / 64.0);
    int common_slabs = 0;
    for (int k = 0; k < 400; ++k) {
      common_slabs +=
          k >= bottom_a && k < bottom_a + height_a && k >= bottom_b && k < bottom_b + height_b;
    }
    const double intersection = ReferenceBevIntersection(a, b) * common_slabs / 64.0;
    const double volume_a = a.l * a.w * a.h, volume_b = b.l * b.w * b.h;
    ASSERT_NEAR(IntersectionVolume(a, b), intersection, 1e-9 * (1 + intersection)) << i;
    const double expected = intersection / (volume_a + volume_b - intersection);
    const double iou = Iou3D(a, b);
    ASSERT_NEAR(iou, expected, 1e-9) << i;
    ASSERT_NEAR(Iou3D(b, a), iou, 1e-12) << i;
    ASSERT_LE(iou, BevIou(a, b) + 1e-12) << i;  // o <= min(h_a, h_b) gives IoU_3D <= IoU_BEV
    overlapping += intersection > 0;
  }
  EXPECT_GT(overlapping, 1000);
}

}  // namespace
}  // namespace stereodet
