// Analytic shapes for the synthetic scenes and their ray intersections.
//
// All shapes live in the rectified camera frame of KITTI (x right, y down, z forward, metres; see
// geometry/box.h). Each primitive has its own orthonormal local frame (`world_from_local`, columns
// are the local axes in the rect frame) centred at `centre`:
//   kBox:       |local x| <= half_extent.x, |local y| <= half_extent.y, |local z| <= half_extent.z
//   kCylinder:  axis along local y, |local y| <= half_extent.y, radius half_extent.x (z ignored)
//   kEllipsoid: (x/hx)^2 + (y/hy)^2 + (z/hz)^2 <= 1
//   kRoundedBox: the box above intersected with the ellipsoid centred at `round_centre` (local)
//               with radii `round_radii`: a box whose edges and corners are rounded away, a
//               convex hull with curved panels (car bodies). Bounds() are the box's; the shape
//               reaches a face only where the ellipsoid holds points of it (always, when it
//               holds the face's centre), which builders that need a tight extent ensure.
// Single precision: scenes span a few hundred metres, so positions are good to well under a
// millimetre, which is far below a pixel at any depth we render.
#ifndef STEREODET_SYNTH_SHAPES_H_
#define STEREODET_SYNTH_SHAPES_H_

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>

namespace stereodet {

inline constexpr float kNoHit = std::numeric_limits<float>::infinity();

// A ray origin + t * direction, t >= 0. `direction` need not be unit length: t is measured in units
// of |direction| (camera rays use direction.z = 1, so t is the depth).
struct Ray {
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();
  Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
  Eigen::Vector3f inv_direction = Eigen::Vector3f(kNoHit, kNoHit, 1.0f);  // 1 / direction

  Ray() = default;
  Ray(const Eigen::Vector3f& o, const Eigen::Vector3f& d) : origin(o), direction(d) {
    inv_direction = d.cwiseInverse();
  }
  Eigen::Vector3f At(float t) const { return origin + t * direction; }
};

// Axis-aligned bounding box in the rect frame.
struct Aabb {
  Eigen::Vector3f min = Eigen::Vector3f::Constant(kNoHit);
  Eigen::Vector3f max = Eigen::Vector3f::Constant(-kNoHit);

  void Extend(const Eigen::Vector3f& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  void Extend(const Aabb& b) {
    min = min.cwiseMin(b.min);
    max = max.cwiseMax(b.max);
  }
  bool Empty() const { return (min.array() > max.array()).any(); }
  Eigen::Vector3f Centre() const { return 0.5f * (min + max); }
  float SurfaceArea() const;
  // Entry distance of `ray` into the box if it enters within (t_min, t_max), else kNoHit.
  // Inline: it is the innermost operation of every BVH traversal.
  float Intersect(const Ray& ray, float t_min, float t_max) const {
    // Slab test. With an infinite inverse direction, (bound - origin) * inf is +-inf, which the
    // min/max handle; 0 * inf (origin exactly on a slab of a parallel ray) gives NaN, and
    // std::min/max with NaN second keep the first argument, so such a ray is treated as inside.
    const float tx0 = (min.x() - ray.origin.x()) * ray.inv_direction.x();
    const float tx1 = (max.x() - ray.origin.x()) * ray.inv_direction.x();
    const float ty0 = (min.y() - ray.origin.y()) * ray.inv_direction.y();
    const float ty1 = (max.y() - ray.origin.y()) * ray.inv_direction.y();
    const float tz0 = (min.z() - ray.origin.z()) * ray.inv_direction.z();
    const float tz1 = (max.z() - ray.origin.z()) * ray.inv_direction.z();
    const float near = std::max(std::max(std::min(tx0, tx1), std::min(ty0, ty1)),
                                std::max(std::min(tz0, tz1), t_min));
    const float far = std::min(std::min(std::max(tx0, tx1), std::max(ty0, ty1)),
                               std::min(std::max(tz0, tz1), t_max));
    return near <= far ? near : kNoHit;
  }
};

enum class ShapeKind : uint8_t { kBox, kCylinder, kEllipsoid, kRoundedBox };

struct Primitive {
  ShapeKind kind = ShapeKind::kBox;
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();                // rect frame, m
  Eigen::Matrix3f world_from_local = Eigen::Matrix3f::Identity();  // orthonormal
  Eigen::Vector3f half_extent = Eigen::Vector3f::Ones();           // m, see the file comment
  int material = 0;                                                // index into Scene::materials
  int object = -1;  // index into Scene::objects, -1 for unlabelled background
  // Offsets the texture coordinates so that copies of one material do not look identical.
  Eigen::Vector2f texture_offset = Eigen::Vector2f::Zero();
  // kRoundedBox only: the rounding ellipsoid, in the local frame (m).
  Eigen::Vector3f round_centre = Eigen::Vector3f::Zero();
  Eigen::Vector3f round_radii = Eigen::Vector3f::Constant(kNoHit);

  Aabb Bounds() const;
  // Smallest t in (t_min, t_max) where `ray` enters the shape, or kNoHit. Rays starting inside
  // return the exit point.
  float Intersect(const Ray& ray, float t_min, float t_max) const;
  // Outward unit normal at a surface point (rect frame).
  Eigen::Vector3f Normal(const Eigen::Vector3f& point) const;
  bool Contains(const Eigen::Vector3f& point, float tolerance = 1e-4f) const;
  Eigen::Vector3f ToLocal(const Eigen::Vector3f& point) const {
    return world_from_local.transpose() * (point - centre);
  }
};

// Builders. `yaw_rad` turns about the rect y axis as KITTI's rotation_y does: the local x axis
// becomes (cos yaw, 0, -sin yaw).
Eigen::Matrix3f RotationY(float yaw_rad);
Primitive MakeBox(const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extent,
                  const Eigen::Matrix3f& world_from_local, int material, int object = -1);
// A cylinder whose axis is world_from_local's y column.
Primitive MakeCylinder(const Eigen::Vector3f& centre, float radius, float half_length,
                       const Eigen::Matrix3f& world_from_local, int material, int object = -1);
Primitive MakeEllipsoid(const Eigen::Vector3f& centre, const Eigen::Vector3f& radii,
                        const Eigen::Matrix3f& world_from_local, int material, int object = -1);
// A box rounded by an ellipsoid (see kRoundedBox). Requires: positive radii and an ellipsoid
// (round_centre, round_radii, local frame) that holds the box's centre; throws
// std::invalid_argument otherwise.
Primitive MakeRoundedBox(const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extent,
                         const Eigen::Matrix3f& world_from_local,
                         const Eigen::Vector3f& round_centre, const Eigen::Vector3f& round_radii,
                         int material, int object = -1);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_SHAPES_H_
