#include "stereodet/eval/frame_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "stereodet/geometry/iou.h"

namespace stereodet {
namespace {

// KittiOverlap's BEV and 3D values, written out from their definition (frame_data.h) on
// BevIntersectionArea, with no shortcut: the reference for the far-apart test of
// FootprintIntersection.
double ReferenceOverlap(OverlapKind kind, const Box3D& d, const Box3D& g) {
  auto footprint = [](Box3D b) {
    if (b.l < 0 && b.w < 0) {
      b.l = -b.l;
      b.w = -b.w;
    }
    return b;
  };
  const Box3D fd = footprint(d), fg = footprint(g);
  const double area =
      fd.l > 0 && fd.w > 0 && fg.l > 0 && fg.w > 0 ? BevIntersectionArea(fd, fg) : 0.0;
  if (kind == OverlapKind::kBev) {
    if (area <= 0) return 0.0;
    return area / (d.l * d.w + g.l * g.w - area);
  }
  const double ymax = std::min(d.location.y(), g.location.y());
  const double ymin = std::max(d.location.y() - d.h, g.location.y() - g.h);
  const double inter = area * std::max(0.0, ymax - ymin);
  if (inter <= 0) return 0.0;
  return inter / (d.h * d.l * d.w + g.h * g.l * g.w - inter);
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Random pairs from overlapping to far apart, including pairs just beyond the reach of the
// circumscribed circles and boxes of very different sizes; every overlap bit for bit the reference.
TEST(KittiOverlap, BevAnd3DEqualTheirDefinitionOnRandomPairs) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> size(0.05, 6.0), angle(-3.2, 3.2), unit(0.0, 1.0);
  int overlapping = 0, apart = 0;
  for (int n = 0; n < 200000; ++n) {
    Object det, label;
    for (Object* o : {&det, &label}) {
      o->box3d.l = size(rng);
      o->box3d.w = size(rng);
      o->box3d.h = size(rng);
      o->box3d.rotation_y = n % 4 == 0 ? 1.57 : angle(rng);  // parallel footprints now and then
      if (n % 50 == 0) o->box3d.l = o->box3d.w = -1;         // KITTI's "not estimated"
    }
    label.box3d.location = Eigen::Vector3d(0.0, 1.6, 20.0);
    // The distance of the centres as a multiple of the largest possible reach, 0 to 1.2.
    const double reach = (det.box3d.l + det.box3d.w + label.box3d.l + label.box3d.w) / 2;
    const double r = 1.2 * unit(rng) * std::abs(reach), t = angle(rng);
    det.box3d.location =
        Eigen::Vector3d(r * std::cos(t), 1.6 + (unit(rng) - 0.5) * 2.0, 20.0 + r * std::sin(t));
    for (const OverlapKind kind : {OverlapKind::kBev, OverlapKind::k3D}) {
      const double got = KittiOverlap(kind, det, label);
      const double want = ReferenceOverlap(kind, det.box3d, label.box3d);
      ASSERT_TRUE(SameBits(got, want)) << "pair " << n << ": " << got << " vs " << want;
      (got > 0 ? overlapping : apart) += 1;
    }
  }
  // Both sides of the shortcut are exercised.
  EXPECT_GT(overlapping, 50000);
  EXPECT_GT(apart, 50000);
}

}  // namespace
}  // namespace stereodet
