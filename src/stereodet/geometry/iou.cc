#include "stereodet/geometry/iou.h"

#include <algorithm>
#include <cmath>

namespace stereodet {

namespace {

struct Point {
  double x, z;
};

// Sine and cosine of an angle, snapped to exact 0 / +-1 when within 1e-12 of a multiple of 90
// degrees. cos(pi/2) is 6e-17, not 0; without the snap a square turned by 90 degrees would overlap
// itself by 1 - 1e-16 instead of 1. The snap moves a corner by at most 1e-12 of the box size.
void SnappedSinCos(double angle, double* s, double* c) {
  *s = std::sin(angle);
  *c = std::cos(angle);
  constexpr double kSnap = 1e-12;
  if (std::abs(*s) < kSnap) {
    *s = 0.0;
    *c = *c > 0 ? 1.0 : -1.0;
  } else if (std::abs(*c) < kSnap) {
    *c = 0.0;
    *s = *s > 0 ? 1.0 : -1.0;
  }
}

// Clips the convex polygon `in` (n vertices) to the half-plane {p : sign * p[axis] <= bound} and
// writes the result to `out`, returning its vertex count. A convex polygon clipped by a half-plane
// gains at most one vertex, so 8 slots suffice for a rectangle clipped four times.
int ClipAxis(const Point* in, int n, int axis, double sign, double bound, Point* out) {
  auto value = [&](const Point& p) { return sign * (axis == 0 ? p.x : p.z) - bound; };
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const Point& p = in[i];
    const Point& q = in[(i + 1) % n];
    const double vp = value(p), vq = value(q);
    if (vp <= 0) out[m++] = p;
    // The edge crosses the line strictly: add the crossing. Points on the line are kept above, so a
    // vertex lying exactly on the boundary is never duplicated.
    if ((vp < 0 && vq > 0) || (vp > 0 && vq < 0)) {
      const double t = vp / (vp - vq);
      Point r{p.x + t * (q.x - p.x), p.z + t * (q.z - p.z)};
      // Put the crossing exactly on the line, so later clips and the area see no rounding residue.
      if (axis == 0)
        r.x = sign * bound;
      else
        r.z = sign * bound;
      out[m++] = r;
    }
  }
  return m;
}

double PolygonArea(const Point* p, int n) {
  double twice = 0.0;
  for (int i = 0; i < n; ++i) {
    const Point& a = p[i];
    const Point& b = p[(i + 1) % n];
    twice += a.x * b.z - b.x * a.z;
  }
  return std::abs(twice) / 2.0;
}

}  // namespace

double IntersectionArea(const Box2D& a, const Box2D& b) {
  const double w = std::min(a.right, b.right) - std::max(a.left, b.left);
  const double h = std::min(a.bottom, b.bottom) - std::max(a.top, b.top);
  return (w > 0 && h > 0) ? w * h : 0.0;
}

double Iou2D(const Box2D& a, const Box2D& b) {
  const double inter = IntersectionArea(a, b);
  if (inter <= 0) return 0.0;
  const double uni = a.Area() + b.Area() - inter;
  return uni > 0 ? std::min(1.0, inter / uni) : 0.0;
}

double BevIntersectionArea(const Box3D& a, const Box3D& b) {
  if (!(a.l > 0 && a.w > 0 && b.l > 0 && b.w > 0)) return 0.0;
  // Work in a's own frame: a becomes the axis-aligned rectangle [-l/2, l/2] x [-w/2, w/2], which we
  // clip b against with four exact axis comparisons. Identical boxes then give identical corners.
  const double dx = b.location.x() - a.location.x();
  const double dz = b.location.z() - a.location.z();
  const double hal = a.l / 2.0, haw = a.w / 2.0;
  const double hbl = b.l / 2.0, hbw = b.w / 2.0;
  // Circumscribed circles apart: no overlap (the common case among all pairs of a frame).
  const double reach = std::hypot(hal, haw) + std::hypot(hbl, hbw);
  if (dx * dx + dz * dz >= reach * reach) return 0.0;

  // Camera frame -> a's frame: rotate by -rotation_y of a. With x' = c x + s z, z' = -s x + c z for
  // a rotation by theta, the inverse is x = c x' - s z', z = s x' + c z'.
  double sa, ca;
  SnappedSinCos(a.rotation_y, &sa, &ca);
  const double cx = ca * dx - sa * dz;
  const double cz = sa * dx + ca * dz;
  double s, c;  // b's rotation relative to a
  SnappedSinCos(b.rotation_y - a.rotation_y, &s, &c);
  if (s == 0.0) {
    // Axis-aligned in a's frame: the intersection is a product of two interval overlaps.
    const double ix = std::min(hal, cx + hbl) - std::max(-hal, cx - hbl);
    const double iz = std::min(haw, cz + hbw) - std::max(-haw, cz - hbw);
    return (ix > 0 && iz > 0) ? ix * iz : 0.0;
  }
  if (c == 0.0) {
    const double ix = std::min(hal, cx + hbw) - std::max(-hal, cx - hbw);
    const double iz = std::min(haw, cz + hbl) - std::max(-haw, cz - hbl);
    return (ix > 0 && iz > 0) ? ix * iz : 0.0;
  }
  const double ox[4] = {hbl, hbl, -hbl, -hbl};
  const double oz[4] = {hbw, -hbw, -hbw, hbw};
  Point poly[8], tmp[8];
  for (int i = 0; i < 4; ++i) {
    poly[i] = Point{c * ox[i] + s * oz[i] + cx, -s * ox[i] + c * oz[i] + cz};
  }
  int n = 4;
  n = ClipAxis(poly, n, 0, 1.0, hal, tmp);
  n = ClipAxis(tmp, n, 0, -1.0, hal, poly);
  n = ClipAxis(poly, n, 1, 1.0, haw, tmp);
  n = ClipAxis(tmp, n, 1, -1.0, haw, poly);
  if (n < 3) return 0.0;
  // Never more than the smaller rectangle: keeps IoU <= 1 under rounding.
  return std::min(PolygonArea(poly, n), std::min(a.l * a.w, b.l * b.w));
}

double BevIou(const Box3D& a, const Box3D& b) {
  const double inter = BevIntersectionArea(a, b);
  if (inter <= 0) return 0.0;
  const double uni = a.l * a.w + b.l * b.w - inter;
  return uni > 0 ? std::min(1.0, inter / uni) : 0.0;
}

namespace {
// The y extent [location.y - h, location.y] (y points down) and its length, computed from the same
// two numbers as the overlap below, so that a box's overlap with itself equals its own height
// exactly.
double YExtent(const Box3D& box) { return box.location.y() - (box.location.y() - box.h); }
}  // namespace

double IntersectionVolume(const Box3D& a, const Box3D& b) {
  const double y_overlap = std::min(a.location.y(), b.location.y()) -
                           std::max(a.location.y() - a.h, b.location.y() - b.h);
  if (!(y_overlap > 0)) return 0.0;
  return BevIntersectionArea(a, b) * y_overlap;
}

double Iou3D(const Box3D& a, const Box3D& b) {
  if (!(a.h > 0 && b.h > 0)) return 0.0;
  const double inter = IntersectionVolume(a, b);
  if (inter <= 0) return 0.0;
  // Volumes as (l * w) * y-extent: the same products as the intersection of a box with itself.
  const double uni = a.l * a.w * YExtent(a) + b.l * b.w * YExtent(b) - inter;
  return uni > 0 ? std::min(1.0, inter / uni) : 0.0;
}

}  // namespace stereodet
