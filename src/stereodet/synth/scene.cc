#include "stereodet/synth/scene.h"

#include <cmath>

namespace stereodet {

Eigen::Vector2f Road::ToRoad(float x, float z) const {
  if (curvature_per_m == 0.0f) {
    const Eigen::Vector2f d(x - origin_xz.x(), z - origin_xz.y());
    return {d.dot(RightXz()), d.dot(forward_xz)};
  }
  return ArcToRoad(origin_xz, forward_xz, curvature_per_m, x, z);
}

float Road::LateralOf(float x, float z) const {
  if (curvature_per_m == 0.0f) {
    return (x - origin_xz.x()) * forward_xz.y() - (z - origin_xz.y()) * forward_xz.x();
  }
  return ArcLateral(origin_xz, forward_xz, curvature_per_m, x, z);
}

Eigen::Vector2f Road::FromRoad(float lateral_m, float along_m) const {
  if (curvature_per_m == 0.0f) return origin_xz + lateral_m * RightXz() + along_m * forward_xz;
  return ArcFromRoad(origin_xz, forward_xz, curvature_per_m, lateral_m, along_m);
}

const SideStreet* Road::SideStreetAt(float along_m) const {
  for (const SideStreet& s : side_streets) {
    if (s.Covers(along_m)) return &s;
  }
  return nullptr;
}

float Road::ForwardYaw() const {
  // A heading (hx, hz) in the rect frame is rotation_y = atan2(-hz, hx) (geometry/box.h).
  return std::atan2(-forward_xz.y(), forward_xz.x());
}

void Scene::Finalize() { bvh_ = Bvh(primitives); }

int Scene::AddMaterial(const Material& material) {
  materials.push_back(material);
  return static_cast<int>(materials.size()) - 1;
}

bool Scene::Occluded(const Ray& ray, float t_min, float t_max, int* hint) const {
  if (hint != nullptr && *hint >= 0 && primitives[*hint].Intersect(ray, t_min, t_max) != kNoHit) {
    return true;
  }
  const RayHit blocker = bvh_.AnyHit(ray, t_min, t_max);
  if (hint != nullptr && blocker.primitive >= 0) *hint = blocker.primitive;
  return blocker.primitive >= 0;
}

float Scene::GroundHit(const Ray& ray, float t_min, float t_max) const {
  if (!ground.Flat()) {
    // Hits beyond max_ground_distance_m are none: a ray that has not met the ground by then need
    // not be followed (a bound that lets the shaped ground reject most rays above the horizon at
    // once).
    const float horizontal_sq =
        ray.direction.x() * ray.direction.x() + ray.direction.z() * ray.direction.z();
    t_max = std::min(t_max, max_ground_distance_m / std::sqrt(std::max(1e-24f, horizontal_sq)));
  } else if (ray.direction.y() <= 0.0f) {
    return kNoHit;
  }
  const float t = ground.Intersect(ray, ground_y_m, t_min, t_max);
  if (t == kNoHit) return kNoHit;
  const float horizontal = t * std::hypot(ray.direction.x(), ray.direction.z());
  return horizontal < max_ground_distance_m ? t : kNoHit;
}

SurfaceHit Scene::MakeHit(const Ray& ray, float t, int primitive) const {
  SurfaceHit hit;
  if (t == kNoHit) return hit;
  hit.t = t;
  hit.point = ray.At(t);
  if (primitive >= 0) {
    const Primitive& p = primitives[primitive];
    hit.kind = SurfaceHit::Kind::kPrimitive;
    hit.normal = p.Normal(hit.point);
    hit.primitive = primitive;
    hit.material = p.material;
    hit.object = p.object;
  } else {
    hit.kind = SurfaceHit::Kind::kGround;
    hit.point.y() = static_cast<float>(
        ground_y_m - ground.HeightAndNormal(hit.point.x(), hit.point.z(), &hit.normal));
    const float lateral = road.LateralOf(hit.point.x(), hit.point.z());
    bool on_road = lateral >= road.left_edge_m && lateral <= road.right_edge_m;
    if (!on_road && !road.side_streets.empty()) {
      const SideStreet* side = road.SideStreetAt(road.ToRoad(hit.point.x(), hit.point.z()).y());
      on_road = side != nullptr && side->OnSide(lateral < road.left_edge_m ? 0 : 1);
    }
    hit.material = on_road ? road_material : offroad_material;
  }
  if (hit.normal.dot(ray.direction) > 0.0f) hit.normal = -hit.normal;
  return hit;
}

SurfaceHit Scene::Trace(const Ray& ray, float t_min, float t_max, int hint) const {
  // The ground first: it is analytic and, for the lower half of every image, the closest hit, so
  // it bounds the BVH search from the start.
  const float ground_t = GroundHit(ray, t_min, t_max);
  if (ground_t != kNoHit) t_max = ground_t;
  RayHit prim_hit;
  if (hint >= 0) {
    const float t = primitives[hint].Intersect(ray, t_min, t_max);
    if (t != kNoHit) {
      prim_hit = {t, hint};
      t_max = t;
    }
  }
  const RayHit closer = bvh_.Intersect(ray, t_min, t_max);
  if (closer.primitive >= 0) prim_hit = closer;
  if (prim_hit.primitive >= 0) return MakeHit(ray, prim_hit.t, prim_hit.primitive);
  return MakeHit(ray, ground_t, -1);
}

}  // namespace stereodet
