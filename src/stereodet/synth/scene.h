// A synthetic street scene: an analytic ground (a plane, or cresting and crowned: road.h) with a
// road on it, primitives (boxes, cylinders, ellipsoids) grouped into labelled objects and
// background clutter, materials and light.
//
// The scene lives in KITTI's rectified camera frame (x right, y down, z forward, metres; the
// origin is the centre of camera 0). The left camera, the right camera and the LiDAR all cast rays
// into this one scene (Scene::Trace), which is what makes images, scans, labels and ground-truth
// disparity agree exactly.
#ifndef STEREODET_SYNTH_SCENE_H_
#define STEREODET_SYNTH_SCENE_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "stereodet/geometry/box.h"
#include "stereodet/synth/bvh.h"
#include "stereodet/synth/road.h"
#include "stereodet/synth/shapes.h"

namespace stereodet {

// How a material's albedo varies over its surface (see texture.h).
enum class Pattern : uint8_t {
  kPlain,     // fine noise only
  kAsphalt,   // grainy asphalt with patches; lane markings come from Road
  kPaving,    // paving stones: a grid of joints, stones with individual tones
  kFacade,    // a building front: walls with rows of windows (albedo2) and floor bands
  kBrick,     // brick courses with mortar joints (albedo2)
  kFence,     // vertical slats with gaps (albedo2)
  kFoliage,   // leaves: strong high-frequency noise
  kGrass,     // grass and soil
  kCarPaint,  // paint with dirt and grime; lights, grille and plate on the front and rear faces,
              // seams, handles and wheel arches (at +-scale_m along the body, if > 0) on the sides
  kGlass,     // dark glass reflecting the sky, the interior behind it; pillars in albedo2
  kCloth,     // clothing: mid-frequency noise and folds
  kWheel,     // tyre (albedo) with a spoked rim (albedo2) on the cylinder's end faces
};

struct Material {
  Pattern pattern = Pattern::kPlain;
  Eigen::Vector3f albedo = Eigen::Vector3f::Constant(0.5f);   // linear RGB in [0, 1]
  Eigen::Vector3f albedo2 = Eigen::Vector3f::Constant(0.1f);  // secondary colour of the pattern
  float contrast = 0.2f;           // relative amplitude of the fine noise
  float scale_m = 1.0f;            // pattern cell size (window pitch, stone, brick, slat), metres
  float specular = 0.0f;           // fraction of sky light mirrored (paint, glass)
  float lidar_reflectance = 0.3f;  // LiDAR intensity at normal incidence, [0, 1]
  // A pattern's variant. kCloth: 0 plain weave with folds, 1 stripes of albedo2 across the
  // garment (period scale_m), 2 checks of albedo2 (cell scale_m), 3 denim (a fine diagonal twill,
  // faded in patches).
  uint8_t variant = 0;
};

// A labelled object (KITTI class) made of consecutive primitives.
struct SceneObject {
  std::string
      type;   // KITTI class: Car, Van, Truck, Pedestrian, Person_sitting, Cyclist, Tram, Misc
  Box3D box;  // the label box (rect frame): the tight extent of the primitives
  int first_primitive = 0;
  int num_primitives = 0;
};

// The road painted on the ground, described in road coordinates: `lateral` (metres to the right of
// the ego lane's centre line) and `along` (metres forward, along that line). The line is a
// circular arc (road.h's ArcToRoad; straight for curvature 0).
struct Road {
  Eigen::Vector2f origin_xz = Eigen::Vector2f::Zero();       // rect (x, z) of road coordinate 0
  Eigen::Vector2f forward_xz = Eigen::Vector2f(0.0f, 1.0f);  // unit, rect (x, z), at along 0
  float curvature_per_m = 0.0f;  // 1 / radius of the bend, > 0 to the right; 0: straight
  float left_edge_m = -5.0f;     // lateral position of the asphalt's left edge (negative)
  float right_edge_m = 5.0f;     // ... and right edge
  struct Marking {
    float lateral_m = 0.0f;
    float width_m = 0.12f;
    bool dashed = false;  // 3 m dash, 6 m gap (German urban roads)
  };
  std::vector<Marking> markings;
  std::vector<SideStreet> side_streets;  // asphalt across the road's edges; no markings in them

  Eigen::Vector2f RightXz() const { return {forward_xz.y(), -forward_xz.x()}; }
  // Road coordinates (lateral, along) of a rect (x, z) point.
  Eigen::Vector2f ToRoad(float x, float z) const;
  // The lateral road coordinate alone (cheaper on a bend: no arc length).
  float LateralOf(float x, float z) const;
  // Rect (x, z) of road coordinates.
  Eigen::Vector2f FromRoad(float lateral_m, float along_m) const;
  // Heading of the road at along 0 as a KITTI rotation_y (objects driving forward along the road).
  float ForwardYaw() const;
  // ... and at `along_m` (on a bend the heading turns by curvature x along).
  float ForwardYawAt(float along_m) const { return ForwardYaw() + curvature_per_m * along_m; }
  // The side street that covers `along_m`, or nullptr.
  const SideStreet* SideStreetAt(float along_m) const;
};

struct Lighting {
  Eigen::Vector3f to_sun = Eigen::Vector3f(0.3f, -0.8f, 0.5f).normalized();  // unit, rect frame
  Eigen::Vector3f sun = Eigen::Vector3f(2.2f, 2.1f, 1.9f);  // irradiance, linear RGB
  Eigen::Vector3f sky_ambient = Eigen::Vector3f(0.55f, 0.6f, 0.7f);
  Eigen::Vector3f sky_zenith = Eigen::Vector3f(0.35f, 0.5f, 0.85f);
  Eigen::Vector3f sky_horizon = Eigen::Vector3f(0.85f, 0.88f, 0.92f);
  float cloudiness = 0.3f;           // [0, 1]
  float haze_per_m = 1.0f / 600.0f;  // extinction: weight of the horizon colour is 1 - exp(-d k)
  float exposure = 1.0f;
  // The camera's white balance (gains on linear R, G, B; as set, not as the light is) and its
  // sensor noise relative to RenderOptions::noise_sigma (gain, temperature), both per frame.
  Eigen::Vector3f white_balance = Eigen::Vector3f::Ones();
  float noise_scale = 1.0f;
  // Shifts the skyline that paint and glass mirror (ReflectedRadiance), per frame.
  float skyline_offset = 0.0f;
};

// What a ray hit.
struct SurfaceHit {
  enum class Kind : uint8_t { kNone, kGround, kPrimitive };
  Kind kind = Kind::kNone;
  float t = kNoHit;                                  // ray parameter
  Eigen::Vector3f point = Eigen::Vector3f::Zero();   // rect frame
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  // unit, facing the ray's origin side
  int primitive = -1;                                // kPrimitive only
  int material = -1;
  int object = -1;  // labelled object index, -1 for background and ground
  bool Hit() const { return kind != Kind::kNone; }
};

struct Scene {
  float ground_y_m = 1.65f;  // rect y of the ground under the camera; the camera is this high
  GroundProfile ground;      // the ground's shape: y = ground_y_m - ground.Height(x, z)
  int road_material = 0;     // ground between the road edges
  int offroad_material = 0;  // ground beyond them (under sidewalks, lawns, verges)
  float max_ground_distance_m = 1500.0f;  // farther ground is treated as horizon
  Road road;
  Lighting light;
  std::vector<Material> materials;
  std::vector<Primitive> primitives;
  std::vector<SceneObject> objects;

  // Builds the acceleration structure; call after the last primitive is added.
  void Finalize();
  const Bvh& bvh() const { return bvh_; }

  // Rect y of the ground at rect (x, z).
  float GroundY(float x, float z) const {
    return ground.Flat() ? ground_y_m : static_cast<float>(ground_y_m - ground.Height(x, z));
  }

  // Closest hit along `ray` with t in (t_min, t_max): ground or primitive.
  // `hint` (optional) names a primitive likely to be hit, e.g. the one the neighbouring pixel's ray
  // hit: testing it first tightens t_max before the BVH search. The result does not depend on it.
  SurfaceHit Trace(const Ray& ray, float t_min = 1e-4f, float t_max = kNoHit, int hint = -1) const;
  // Whether a primitive blocks `ray` within (t_min, t_max) (the ground never does). `hint` (in,
  // out, optional): a primitive to test first; set to the blocker found, if any. Shadow rays of
  // neighbouring pixels are usually blocked by the same primitive, which then costs one test.
  bool Occluded(const Ray& ray, float t_min, float t_max, int* hint = nullptr) const;

  // The parts of Trace, for callers with their own search structure (the cameras' screen bins):
  // the ground's ray parameter in (t_min, t_max), or kNoHit ...
  float GroundHit(const Ray& ray, float t_min, float t_max) const;
  // ... and the full hit record for a hit at `t` on `primitive` (-1: the ground; with t = kNoHit:
  // no hit).
  SurfaceHit MakeHit(const Ray& ray, float t, int primitive) const;

  // Adds a material and returns its index.
  int AddMaterial(const Material& material);

 private:
  Bvh bvh_;
};

}  // namespace stereodet

#endif  // STEREODET_SYNTH_SCENE_H_
