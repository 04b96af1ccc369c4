#include "stereodet/synth/shapes.h"

#include <algorithm>
#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

float Aabb::SurfaceArea() const {
  if (Empty()) return 0.0f;
  const Eigen::Vector3f e = max - min;
  return 2.0f * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
}

Aabb Primitive::Bounds() const {
  Eigen::Vector3f extent = Eigen::Vector3f::Zero();
  const Eigen::Matrix3f abs_r = world_from_local.cwiseAbs();
  switch (kind) {
    case ShapeKind::kBox:
    case ShapeKind::kRoundedBox:  // the box encloses it
      extent = abs_r * half_extent;
      break;
    case ShapeKind::kCylinder: {
      // Axis a = column 1: extent_i = h |a_i| + r sqrt(1 - a_i^2).
      const Eigen::Vector3f axis = world_from_local.col(1);
      for (int i = 0; i < 3; ++i) {
        extent[i] = half_extent.y() * std::abs(axis[i]) +
                    half_extent.x() * std::sqrt(std::max(0.0f, 1.0f - axis[i] * axis[i]));
      }
      break;
    }
    case ShapeKind::kEllipsoid:
      for (int i = 0; i < 3; ++i) {
        extent[i] = world_from_local.row(i).cwiseProduct(half_extent.transpose()).norm();
      }
      break;
  }
  Aabb box;
  box.min = centre - extent;
  box.max = centre + extent;
  return box;
}

namespace {

float IntersectLocalBox(const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                        const Eigen::Vector3f& h, float t_min, float t_max) {
  float near = -kNoHit, far = kNoHit;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) {
      if (o[a] < -h[a] || o[a] > h[a]) return kNoHit;
      continue;
    }
    const float inv = 1.0f / d[a];
    float t0 = (-h[a] - o[a]) * inv;
    float t1 = (h[a] - o[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    near = std::max(near, t0);
    far = std::min(far, t1);
    if (near > far) return kNoHit;
  }
  if (near > t_min && near < t_max) return near;
  if (far > t_min && far < t_max && near <= t_min) return far;  // starts inside
  return kNoHit;
}

// The ray's parameter interval [near, far] inside the local box, or false if it misses.
bool LocalBoxInterval(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Eigen::Vector3f& h,
                      float* near_out, float* far_out) {
  float near = -kNoHit, far = kNoHit;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) {
      if (o[a] < -h[a] || o[a] > h[a]) return false;
      continue;
    }
    const float inv = 1.0f / d[a];
    float t0 = (-h[a] - o[a]) * inv;
    float t1 = (h[a] - o[a]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    near = std::max(near, t0);
    far = std::min(far, t1);
    if (near > far) return false;
  }
  *near_out = near;
  *far_out = far;
  return true;
}

// Intersection of two convex sets: the ray is inside both on the intersection of its intervals.
float IntersectLocalRoundedBox(const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                               const Primitive& p, float t_min, float t_max) {
  float near = 0.0f, far = 0.0f;
  if (!LocalBoxInterval(o, d, p.half_extent, &near, &far)) return kNoHit;
  const Eigen::Vector3f inv = p.round_radii.cwiseInverse();
  const Eigen::Vector3f os = (o - p.round_centre).cwiseProduct(inv), ds = d.cwiseProduct(inv);
  const float a = ds.squaredNorm(), b = os.dot(ds), c = os.squaredNorm() - 1.0f;
  const float disc = b * b - a * c;
  if (disc < 0.0f || a <= 0.0f) return kNoHit;
  const float s = std::sqrt(disc);
  near = std::max(near, (-b - s) / a);
  far = std::min(far, (-b + s) / a);
  if (near > far) return kNoHit;
  if (near > t_min && near < t_max) return near;
  if (far > t_min && far < t_max && near <= t_min) return far;  // starts inside
  return kNoHit;
}

// Smallest root of a t^2 + 2 b t + c = 0 inside (t_min, t_max).
float SmallestRoot(float a, float b, float c, float t_min, float t_max, float* other) {
  const float disc = b * b - a * c;
  if (disc < 0.0f || a <= 0.0f) return kNoHit;
  const float s = std::sqrt(disc);
  const float t0 = (-b - s) / a;
  const float t1 = (-b + s) / a;
  *other = t1;
  if (t0 > t_min && t0 < t_max) return t0;
  if (t1 > t_min && t1 < t_max) return t1;
  return kNoHit;
}

float IntersectLocalCylinder(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float r, float h,
                             float t_min, float t_max) {
  float best = kNoHit;
  // Side: x^2 + z^2 = r^2 with |y| <= h.
  const float a = d.x() * d.x() + d.z() * d.z();
  const float b = o.x() * d.x() + o.z() * d.z();
  const float c = o.x() * o.x() + o.z() * o.z() - r * r;
  if (a > 0.0f) {
    const float disc = b * b - a * c;
    if (disc >= 0.0f) {
      const float s = std::sqrt(disc);
      for (float t : {(-b - s) / a, (-b + s) / a}) {
        if (t > t_min && t < t_max && t < best && std::abs(o.y() + t * d.y()) <= h) {
          best = t;
          break;
        }
      }
    }
  }
  // Caps: y = +-h with x^2 + z^2 <= r^2.
  if (d.y() != 0.0f) {
    for (float cap : {-h, h}) {
      const float t = (cap - o.y()) / d.y();
      if (t > t_min && t < t_max && t < best) {
        const float x = o.x() + t * d.x(), z = o.z() + t * d.z();
        if (x * x + z * z <= r * r) best = t;
      }
    }
  }
  return best;
}

}  // namespace

float Primitive::Intersect(const Ray& ray, float t_min, float t_max) const {
  const Eigen::Matrix3f local_from_world = world_from_local.transpose();
  const Eigen::Vector3f o = local_from_world * (ray.origin - centre);
  const Eigen::Vector3f d = local_from_world * ray.direction;
  switch (kind) {
    case ShapeKind::kBox:
      return IntersectLocalBox(o, d, half_extent, t_min, t_max);
    case ShapeKind::kCylinder:
      return IntersectLocalCylinder(o, d, half_extent.x(), half_extent.y(), t_min, t_max);
    case ShapeKind::kEllipsoid: {
      const Eigen::Vector3f inv = half_extent.cwiseInverse();
      const Eigen::Vector3f os = o.cwiseProduct(inv), ds = d.cwiseProduct(inv);
      float other = 0.0f;
      return SmallestRoot(ds.squaredNorm(), os.dot(ds), os.squaredNorm() - 1.0f, t_min, t_max,
                          &other);
    }
    case ShapeKind::kRoundedBox:
      return IntersectLocalRoundedBox(o, d, *this, t_min, t_max);
  }
  return kNoHit;
}

Eigen::Vector3f Primitive::Normal(const Eigen::Vector3f& point) const {
  const Eigen::Vector3f p = ToLocal(point);
  Eigen::Vector3f n = Eigen::Vector3f::Zero();
  switch (kind) {
    case ShapeKind::kRoundedBox: {
      // The ellipsoid's surface if the point is nearer to it than to every face: the distance to
      // it is estimated to first order, (1 - e) / |grad e| with e the ellipsoid's quadratic form.
      const Eigen::Vector3f q = (p - round_centre).cwiseQuotient(round_radii);
      const Eigen::Vector3f grad = 2.0f * q.cwiseQuotient(round_radii);
      const float gap = (1.0f - q.squaredNorm()) / std::max(grad.norm(), 1e-6f);
      const float box_gap = (half_extent - p.cwiseAbs()).minCoeff();
      if (gap < box_gap) {
        n = grad.normalized();
        break;
      }
      [[fallthrough]];
    }
    case ShapeKind::kBox: {
      // The face whose slab the point is closest to (relative to the half extent).
      int best = 0;
      float best_gap = kNoHit;
      for (int a = 0; a < 3; ++a) {
        const float gap = half_extent[a] - std::abs(p[a]);
        if (gap < best_gap) {
          best_gap = gap;
          best = a;
        }
      }
      n[best] = p[best] >= 0.0f ? 1.0f : -1.0f;
      break;
    }
    case ShapeKind::kCylinder: {
      const float side_gap = half_extent.x() - std::hypot(p.x(), p.z());
      const float cap_gap = half_extent.y() - std::abs(p.y());
      if (cap_gap < side_gap) {
        n.y() = p.y() >= 0.0f ? 1.0f : -1.0f;
      } else {
        n = Eigen::Vector3f(p.x(), 0.0f, p.z()).normalized();
      }
      break;
    }
    case ShapeKind::kEllipsoid:
      n = p.cwiseQuotient(half_extent.cwiseProduct(half_extent)).normalized();
      break;
  }
  return world_from_local * n;
}

bool Primitive::Contains(const Eigen::Vector3f& point, float tolerance) const {
  const Eigen::Vector3f p = ToLocal(point);
  switch (kind) {
    case ShapeKind::kBox:
      return (p.cwiseAbs().array() <= half_extent.array() + tolerance).all();
    case ShapeKind::kCylinder:
      return std::abs(p.y()) <= half_extent.y() + tolerance &&
             std::hypot(p.x(), p.z()) <= half_extent.x() + tolerance;
    case ShapeKind::kEllipsoid: {
      const Eigen::Vector3f grown = half_extent.array() + tolerance;
      return p.cwiseQuotient(grown).squaredNorm() <= 1.0f;
    }
    case ShapeKind::kRoundedBox: {
      const Eigen::Vector3f grown = round_radii.array() + tolerance;
      return (p.cwiseAbs().array() <= half_extent.array() + tolerance).all() &&
             (p - round_centre).cwiseQuotient(grown).squaredNorm() <= 1.0f;
    }
  }
  return false;
}

Eigen::Matrix3f RotationY(float yaw_rad) {
  const float c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  Eigen::Matrix3f r;
  r << c, 0.0f, s,       //
      0.0f, 1.0f, 0.0f,  //
      -s, 0.0f, c;
  return r;
}

Primitive MakeBox(const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extent,
                  const Eigen::Matrix3f& world_from_local, int material, int object) {
  Primitive p;
  p.kind = ShapeKind::kBox;
  p.centre = centre;
  p.half_extent = half_extent;
  p.world_from_local = world_from_local;
  p.material = material;
  p.object = object;
  return p;
}

Primitive MakeCylinder(const Eigen::Vector3f& centre, float radius, float half_length,
                       const Eigen::Matrix3f& world_from_local, int material, int object) {
  Primitive p = MakeBox(centre, Eigen::Vector3f(radius, half_length, radius), world_from_local,
                        material, object);
  p.kind = ShapeKind::kCylinder;
  return p;
}

Primitive MakeEllipsoid(const Eigen::Vector3f& centre, const Eigen::Vector3f& radii,
                        const Eigen::Matrix3f& world_from_local, int material, int object) {
  Primitive p = MakeBox(centre, radii, world_from_local, material, object);
  p.kind = ShapeKind::kEllipsoid;
  return p;
}

Primitive MakeRoundedBox(const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extent,
                         const Eigen::Matrix3f& world_from_local,
                         const Eigen::Vector3f& round_centre, const Eigen::Vector3f& round_radii,
                         int material, int object) {
  STEREODET_CHECK((round_radii.array() > 0.0f).all())
      << "rounded box: radii must be positive, got " << round_radii.transpose();
  STEREODET_CHECK(round_centre.cwiseQuotient(round_radii).squaredNorm() < 1.0f)
      << "rounded box: the ellipsoid (centre " << round_centre.transpose() << ", radii "
      << round_radii.transpose() << ") does not hold the box's centre";
  Primitive p = MakeBox(centre, half_extent, world_from_local, material, object);
  p.kind = ShapeKind::kRoundedBox;
  p.round_centre = round_centre;
  p.round_radii = round_radii;
  return p;
}

}  // namespace stereodet
