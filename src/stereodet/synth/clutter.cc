#include "stereodet/synth/clutter.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "stereodet/synth/materials.h"
#include "stereodet/synth/shapes.h"

namespace stereodet {

namespace {

// Parts in the item's local frame: x its front, heights positive up, z across; the origin is the
// base. Placed into the scene by Emit().
class ClutterParts {
 public:
  // Box spanning [x0, x1] x heights [h0, h1] x [z0, z1].
  void Box(float x0, float x1, float h0, float h1, float z0, float z1, int material) {
    parts_.push_back(MakeBox(Eigen::Vector3f(0.5f * (x0 + x1), -0.5f * (h0 + h1), 0.5f * (z0 + z1)),
                             Eigen::Vector3f(0.5f * (x1 - x0), 0.5f * (h1 - h0), 0.5f * (z1 - z0)),
                             Eigen::Matrix3f::Identity(), material));
  }
  // Upright cylinder at (x, z) from height h0 to h1.
  void Upright(float x, float z, float radius, float h0, float h1, int material) {
    parts_.push_back(MakeCylinder(Eigen::Vector3f(x, -0.5f * (h0 + h1), z), radius,
                                  0.5f * (h1 - h0), Eigen::Matrix3f::Identity(), material));
  }
  // A disc facing x (a round sign): a cylinder whose axis runs along local x.
  void Disc(float x, float h, float z, float radius, float thickness, int material) {
    Eigen::Matrix3f axis_x;  // columns: local axes y, x, -z (right-handed)
    axis_x << 0, 1, 0,       //
        1, 0, 0,             //
        0, 0, -1;
    parts_.push_back(
        MakeCylinder(Eigen::Vector3f(x, -h, z), radius, 0.5f * thickness, axis_x, material));
  }
  void Ellipsoid(float x, float h, float z, const Eigen::Vector3f& radii, int material) {
    parts_.push_back(
        MakeEllipsoid(Eigen::Vector3f(x, -h, z), radii, Eigen::Matrix3f::Identity(), material));
  }
  // Appends the parts placed at `base` turned by `yaw_rad`, each with its own texture offset.
  ClutterPlacement Emit(Scene& scene, const Eigen::Vector3f& base, float yaw_rad, Rng& rng) {
    const Eigen::Matrix3f rot = RotationY(yaw_rad);
    ClutterPlacement out;
    out.first_primitive = static_cast<int>(scene.primitives.size());
    out.num_primitives = static_cast<int>(parts_.size());
    float top = 0.0f;
    for (Primitive p : parts_) {
      top = std::max(top, -p.Bounds().min.y());
      p.centre = base + rot * p.centre;
      p.world_from_local = rot * p.world_from_local;
      p.object = -1;
      const float du = static_cast<float>(rng.Uniform(0.0, 50.0));
      p.texture_offset = Eigen::Vector2f(du, 0.0f);
      scene.primitives.push_back(p);
    }
    out.height_m = top;
    return out;
  }

 private:
  std::vector<Primitive> parts_;
};

int Metal(Scene& scene, Rng& rng) {
  return scene.AddMaterial(
      MakeMaterial(Pattern::kPlain, Vary(rng, Rgb(0.42, 0.43, 0.44), 0.2), 0.3f, 0.45f));
}

// Sign faces: white, blue, red or yellow, retroreflective (high LiDAR reflectance).
int SignFace(Scene& scene, Rng& rng) {
  const Eigen::Vector3f colour = std::vector<Eigen::Vector3f>{
      Rgb(0.75, 0.75, 0.72), Rgb(0.04, 0.12, 0.45), Rgb(0.5, 0.05, 0.04),
      Rgb(0.7, 0.55, 0.06)}[rng.Categorical({0.35, 0.3, 0.2, 0.15})];
  return scene.AddMaterial(MakeMaterial(Pattern::kPlain, Vary(rng, colour, 0.1), 0.25f, 0.9f));
}

void SignPost(ClutterParts& p, Scene& scene, Rng& rng) {
  const float h = static_cast<float>(rng.Uniform(2.6, 3.2));
  const float r = static_cast<float>(rng.Uniform(0.03, 0.04));
  p.Upright(0.0f, 0.0f, r, 0.0f, h, Metal(scene, rng));
  const int signs = rng.Bernoulli(0.4) ? 2 : 1;
  float centre = h - 0.36f;
  for (int k = 0; k < signs; ++k) {
    const int face = SignFace(scene, rng);
    switch (rng.Categorical({0.4, 0.4, 0.2})) {
      case 0:  // square (or a diamond's bounding square), 60 cm
        p.Box(r, r + 0.02f, centre - 0.3f, centre + 0.3f, -0.3f, 0.3f, face);
        centre -= 0.68f;
        break;
      case 1:  // round, 60-70 cm across
        p.Disc(r + 0.01f, centre, 0.0f, static_cast<float>(rng.Uniform(0.3, 0.35)), 0.02f, face);
        centre -= 0.76f;
        break;
      default:  // an additional plate or a street name, 80 x 25 cm
        p.Box(r, r + 0.02f, centre + 0.11f, centre + 0.36f, -0.4f, 0.4f, face);
        centre -= 0.4f;
        break;
    }
  }
}

void LampPost(ClutterParts& p, Scene& scene, Rng& rng) {
  const float h = static_cast<float>(rng.Uniform(5.0, 8.0));
  const int metal = Metal(scene, rng);
  p.Upright(0.0f, 0.0f, 0.09f, 0.0f, 1.2f, metal);  // the foot
  p.Upright(0.0f, 0.0f, 0.06f, 1.2f, h, metal);
  const float arm = static_cast<float>(rng.Uniform(1.2, 2.0));
  p.Box(0.0f, arm, h - 0.05f, h, -0.03f, 0.03f, metal);
  const int lamp = scene.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.2, 0.2, 0.21), 0.2f));
  p.Box(arm - 0.5f, arm, h - 0.15f, h - 0.05f, -0.13f, 0.13f, lamp);
}

void Bin(ClutterParts& p, Scene& scene, Rng& rng) {
  const Eigen::Vector3f colour =
      std::vector<Eigen::Vector3f>{Rgb(0.08, 0.2, 0.1), Rgb(0.25, 0.25, 0.26), Rgb(0.6, 0.22, 0.04),
                                   Rgb(0.05, 0.05, 0.06)}[rng.Categorical({0.35, 0.3, 0.2, 0.15})];
  const int body = scene.AddMaterial(MakeMaterial(Pattern::kPlain, Vary(rng, colour, 0.15), 0.35f));
  const float top = static_cast<float>(rng.Uniform(0.8, 1.0));
  if (rng.Bernoulli(0.6)) {  // round, on a post
    const float r = static_cast<float>(rng.Uniform(0.2, 0.26));
    p.Upright(0.0f, 0.0f, 0.04f, 0.0f, top - 0.5f, Metal(scene, rng));
    p.Upright(0.0f, 0.0f, r, top - 0.55f, top, body);
  } else {  // square, standing on the ground, with a darker lid
    const float half = static_cast<float>(rng.Uniform(0.22, 0.3));
    p.Box(-half, half, 0.0f, top - 0.04f, -half, half, body);
    const int lid = scene.AddMaterial(MakeMaterial(Pattern::kPlain, 0.5f * colour, 0.2f));
    p.Box(-half - 0.02f, half + 0.02f, top - 0.04f, top, -half - 0.02f, half + 0.02f, lid);
  }
}

void Bollard(ClutterParts& p, Scene& scene, Rng& rng) {
  const float h = static_cast<float>(rng.Uniform(0.8, 1.1));
  const float r = static_cast<float>(rng.Uniform(0.07, 0.1));
  const Eigen::Vector3f colour =
      rng.Bernoulli(0.6) ? Rgb(0.07, 0.07, 0.075) : Rgb(0.45, 0.05, 0.04);
  const int body = scene.AddMaterial(MakeMaterial(Pattern::kPlain, colour, 0.3f));
  const float cap = 0.6f * r;
  p.Upright(0.0f, 0.0f, r, 0.0f, h - cap, body);
  p.Ellipsoid(0.0f, h - cap, 0.0f, Eigen::Vector3f(r, cap, r), body);
  const int band =
      scene.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.75, 0.75, 0.72), 0.1f, 0.9f));
  p.Upright(0.0f, 0.0f, r + 0.005f, h - cap - 0.2f, h - cap - 0.12f, band);
}

void Cabinet(ClutterParts& p, Scene& scene, Rng& rng) {
  const float w = static_cast<float>(rng.Uniform(0.5, 1.4));
  const float d = static_cast<float>(rng.Uniform(0.3, 0.5));
  const float h = static_cast<float>(rng.Uniform(1.0, 1.5));
  // Grey or beige sheet metal, blotched by posters and graffiti (strong noise).
  const Eigen::Vector3f colour = rng.Bernoulli(0.6) ? Rgb(0.55, 0.56, 0.52) : Rgb(0.35, 0.4, 0.33);
  const int body = scene.AddMaterial(MakeMaterial(Pattern::kPlain, Vary(rng, colour, 0.15), 0.55f));
  const int dark = scene.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.1, 0.1, 0.1), 0.3f));
  p.Box(-0.5f * d + 0.03f, 0.5f * d - 0.03f, 0.0f, 0.1f, -0.5f * w + 0.03f, 0.5f * w - 0.03f, dark);
  p.Box(-0.5f * d, 0.5f * d, 0.1f, h - 0.04f, -0.5f * w, 0.5f * w, body);
  p.Box(-0.5f * d - 0.03f, 0.5f * d + 0.03f, h - 0.04f, h, -0.5f * w - 0.03f, 0.5f * w + 0.03f,
        dark);
}

}  // namespace

double ClutterFootprintRadius(ClutterKind kind) {
  switch (kind) {
    case ClutterKind::kSignPost:
      return 0.45;  // a 0.8 m plate beside a 4 cm post
    case ClutterKind::kLampPost:
      return 0.1;
    case ClutterKind::kBin:
      return 0.46;  // the square bin's lid at its corners
    case ClutterKind::kBollard:
      return 0.11;
    case ClutterKind::kCabinet:
      return 0.8;
  }
  return 1.0;
}

double ClutterMaxHeight(ClutterKind kind) {
  switch (kind) {
    case ClutterKind::kSignPost:
      return 3.2;
    case ClutterKind::kLampPost:
      return 8.0;
    case ClutterKind::kBin:
      return 1.0;
    case ClutterKind::kBollard:
      return 1.1;
    case ClutterKind::kCabinet:
      return 1.5;
  }
  return 8.0;
}

ClutterPlacement AddClutter(Scene& scene, ClutterKind kind, const Eigen::Vector3f& base_rect,
                            float yaw_rad, Rng& rng) {
  ClutterParts parts;
  switch (kind) {
    case ClutterKind::kSignPost:
      SignPost(parts, scene, rng);
      break;
    case ClutterKind::kLampPost:
      LampPost(parts, scene, rng);
      break;
    case ClutterKind::kBin:
      Bin(parts, scene, rng);
      break;
    case ClutterKind::kBollard:
      Bollard(parts, scene, rng);
      break;
    case ClutterKind::kCabinet:
      Cabinet(parts, scene, rng);
      break;
  }
  return parts.Emit(scene, base_rect, yaw_rad, rng);
}

}  // namespace stereodet
