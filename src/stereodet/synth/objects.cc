#include "stereodet/synth/objects.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "stereodet/synth/materials.h"
#include "stereodet/util/check.h"

namespace stereodet {

double Round2(double x) { return std::round(x * 100.0) / 100.0; }

namespace {

// Object parts, built in the object's local frame: x forward (the length), y down, z across (the
// width), the origin on the ground. Heights are given positive (metres above the ground).

class Parts {
 public:
  // Axis-aligned local box spanning [x0, x1] x heights [h0, h1] x [z0, z1].
  void Box(float x0, float x1, float h0, float h1, float z0, float z1, int material) {
    parts_.push_back(MakeBox(Eigen::Vector3f(0.5f * (x0 + x1), -0.5f * (h0 + h1), 0.5f * (z0 + z1)),
                             Eigen::Vector3f(0.5f * (x1 - x0), 0.5f * (h1 - h0), 0.5f * (z1 - z0)),
                             Eigen::Matrix3f::Identity(), material));
  }
  // Box() rounded by an ellipsoid with radii `radii` (x, height, z) whose centre is offset from the
  // box's centre by `offset` (x, up, z): curved panels (see kRoundedBox).
  void RoundedBox(float x0, float x1, float h0, float h1, float z0, float z1,
                  const Eigen::Vector3f& offset, const Eigen::Vector3f& radii, int material) {
    parts_.push_back(
        MakeRoundedBox(Eigen::Vector3f(0.5f * (x0 + x1), -0.5f * (h0 + h1), 0.5f * (z0 + z1)),
                       Eigen::Vector3f(0.5f * (x1 - x0), 0.5f * (h1 - h0), 0.5f * (z1 - z0)),
                       Eigen::Matrix3f::Identity(),
                       Eigen::Vector3f(offset.x(), -offset.y(), offset.z()), radii, material));
  }
  // A wheel: a cylinder with its axis across (local z).
  void Wheel(float x, float z, float radius, float width, int material) {
    Eigen::Matrix3f axis_z;
    axis_z << 1, 0, 0,  //
        0, 0, -1,       //
        0, 1, 0;
    parts_.push_back(
        MakeCylinder(Eigen::Vector3f(x, -radius, z), radius, 0.5f * width, axis_z, material));
  }
  // A box from point a to point b (given as (x, height, z)), with half thicknesses across.
  void Segment(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float half_x, float half_z,
               int material) {
    const Eigen::Vector3f pa(a.x(), -a.y(), a.z()), pb(b.x(), -b.y(), b.z());
    const Eigen::Vector3f axis = (pb - pa).normalized();
    Eigen::Vector3f across = Eigen::Vector3f::UnitZ();
    if (std::abs(axis.dot(across)) > 0.9f) across = Eigen::Vector3f::UnitX();
    across = (across - across.dot(axis) * axis).normalized();
    Eigen::Matrix3f r;
    r.col(1) = axis;
    r.col(2) = across;
    r.col(0) = axis.cross(across);
    parts_.push_back(MakeBox(
        0.5f * (pa + pb), Eigen::Vector3f(half_x, 0.5f * (pb - pa).norm(), half_z), r, material));
  }
  void Ellipsoid(const Eigen::Vector3f& centre, const Eigen::Vector3f& radii, int material) {
    parts_.push_back(MakeEllipsoid(Eigen::Vector3f(centre.x(), -centre.y(), centre.z()), radii,
                                   Eigen::Matrix3f::Identity(), material));
  }
  std::vector<Primitive>& parts() { return parts_; }

 private:
  std::vector<Primitive> parts_;
};

struct VehicleMaterials {
  int paint, glass, tyre, dark;
};

VehicleMaterials AddVehicleMaterials(Scene& scene, Rng& rng, const Eigen::Vector3f& colour) {
  Material paint = MakeMaterial(Pattern::kCarPaint, colour, 0.04f);
  paint.specular = 0.12f;
  paint.scale_m = 0.0f;  // no wheel arches unless the builder sets the axle position
  Material glass = MakeMaterial(Pattern::kGlass, Rgb(0.05, 0.055, 0.06), 0.8f, 0.05f);
  glass.specular = 0.22f;
  glass.albedo2 = colour;  // pillars and frames
  Material tyre = MakeMaterial(Pattern::kWheel, Rgb(0.055, 0.055, 0.055), 0.45f, 0.04f);
  // Rims: silver alloy mostly, some black or dark grey.
  tyre.albedo2 = rng.Bernoulli(0.75) ? Vary(rng, Rgb(0.5, 0.5, 0.52), 0.2) : Rgb(0.08, 0.08, 0.09);
  Material dark = MakeMaterial(Pattern::kPlain, Vary(rng, Rgb(0.06, 0.06, 0.06), 0.3), 0.3f);
  return {scene.AddMaterial(paint), scene.AddMaterial(glass), scene.AddMaterial(tyre),
          scene.AddMaterial(dark)};
}

// Returns the axles' distance from the body's centre (for the wheel arches of the paint).
// A curved hull in three body types: a saloon (bonnet, cabin, boot), a hatchback (the cabin runs to
// a steep tail) and an estate or SUV (a long cabin, more of them among the tall cars). Parts: the
// lower body (rounded: curved bonnet, nose, tail and flanks), the glass cabin (rounded from its
// bottom: raked windscreen and rear window, tumblehome), the roof over it, four wheels. The lower
// body spans the length and width, the roof the height, so the label box stays tight.
// It takes four draws from `rng` (as the box-shaped car before it did, so a scene's layout and
// colours do not change with the car model) and draws the shape from a generator seeded by one.
float BuildCar(Parts& p, float l, float w, float h, const VehicleMaterials& m, Rng& rng) {
  const bool tall = h > 1.6f;
  const float r = static_cast<float>(rng.Uniform(0.29, 0.33)) + (tall ? 0.03f : 0.0f);
  const float shoulder = h * static_cast<float>(rng.Uniform(0.55, 0.62));
  Rng shape(rng.Next());
  const float axle = 0.5f * l - static_cast<float>(rng.Uniform(0.68, 0.85));
  const double pick = shape.Uniform(0.0, 1.0);
  enum { kSaloon, kHatchback, kEstate } body;
  if (tall) {
    body = pick < 0.6 ? kEstate : pick < 0.85 ? kHatchback : kSaloon;
  } else {
    body = pick < 0.45 ? kSaloon : pick < 0.8 ? kHatchback : kEstate;
  }
  const float body_half_w = 0.5f * w - 0.03f;
  // Lower body: the ellipsoid's centre lies below the box's, so the shoulders and the bonnet's
  // front are rounded more than the sills.
  const float hx = 0.5f * l, hy = 0.5f * (shoulder - 0.2f), hz = body_half_w;
  // (Named draws: the order of a call's arguments is unspecified.) The plan stays nearly
  // rectangular along the doors, the corners round off.
  const float round_x = static_cast<float>(shape.Uniform(1.2, 1.3));
  const float round_y = static_cast<float>(shape.Uniform(1.5, 1.8));
  const float round_z = static_cast<float>(shape.Uniform(1.1, 1.18));
  p.RoundedBox(-hx, hx, 0.2f, shoulder, -hz, hz, Eigen::Vector3f(0.0f, -0.3f * hy, 0.0f),
               Eigen::Vector3f(round_x * hx, round_y * hy, round_z * hz), m.paint);
  // Cabin: length, rear end, and where its rounding centre sits (behind the middle: a steeper
  // tail than windscreen).
  float cabin_l = 0.0f, cabin_rear = 0.0f, lean = 0.0f, top = 0.0f;
  switch (body) {
    case kSaloon:
      cabin_l = l * static_cast<float>(shape.Uniform(0.44, 0.52));
      cabin_rear = -0.05f * l - 0.5f * cabin_l;
      lean = static_cast<float>(shape.Uniform(-0.1, 0.05));
      top = static_cast<float>(shape.Uniform(0.42, 0.55));
      break;
    case kHatchback:
      cabin_l = l * static_cast<float>(shape.Uniform(0.5, 0.58));
      cabin_rear = -0.5f * l + static_cast<float>(shape.Uniform(0.15, 0.3));
      lean = static_cast<float>(shape.Uniform(-0.3, -0.15));
      top = static_cast<float>(shape.Uniform(0.45, 0.58));
      break;
    case kEstate:
      cabin_l = l * static_cast<float>(shape.Uniform(0.58, 0.68));
      cabin_rear = -0.5f * l + static_cast<float>(shape.Uniform(0.1, 0.2));
      lean = static_cast<float>(shape.Uniform(-0.4, -0.25));
      top = static_cast<float>(shape.Uniform(0.55, 0.68));
      break;
  }
  const float roof_t = 0.05f;
  const float cabin_bottom = shoulder - 0.06f, cabin_top = h - roof_t + 0.02f;
  const float cx = 0.5f * cabin_l, cy = 0.5f * (cabin_top - cabin_bottom);
  const float cz = body_half_w - 0.1f;
  const float cabin_mid = cabin_rear + cx;
  // The rounding ellipsoid sits at the cabin's bottom, at `lean` half lengths from its middle: it
  // reaches the cabin's front at the bottom and `top` of its half length above the centre at
  // the top; across, the top is 80 % of the width (tumblehome).
  const float ox = lean * cx;
  const float rx = 1.02f * (cx - ox);
  const float top_reach = top * cx / rx;  // sqrt(1 - (2 cy / ry)^2) at the top
  const float ry = 2.0f * cy / std::sqrt(1.0f - top_reach * top_reach);
  const float rz = 0.8f * cz / top_reach;
  p.RoundedBox(cabin_rear, cabin_rear + cabin_l, cabin_bottom, cabin_top, -cz, cz,
               Eigen::Vector3f(ox, -cy, 0.0f), Eigen::Vector3f(rx, ry, rz), m.glass);
  // Roof: over the cabin's top, its plan rounded like the glass's elliptical top.
  const float roof_front = std::min(cx, ox + rx * top_reach) + 0.02f;
  const float roof_rear = std::max(-cx, ox - rx * top_reach) - 0.02f;
  const float roof_hx = 0.5f * (roof_front - roof_rear), roof_hz = std::min(cz, rz * top_reach);
  p.RoundedBox(cabin_mid + roof_rear, cabin_mid + roof_front, h - roof_t, h, -roof_hz, roof_hz,
               Eigen::Vector3f::Zero(),
               Eigen::Vector3f(1.15f * roof_hx, 4.0f * roof_t, 1.15f * roof_hz), m.paint);
  for (float x : {-axle, axle}) {
    for (float z : {-0.5f * w + 0.1f, 0.5f * w - 0.1f}) p.Wheel(x, z, r, 0.2f, m.tyre);
  }
  return axle;
}

void BuildVan(Parts& p, float l, float w, float h, const VehicleMaterials& m, Rng& rng) {
  const float half_w = 0.5f * w - 0.03f;
  p.Box(-0.5f * l, 0.5f * l, 0.3f, 1.05f, -half_w, half_w, m.paint);
  p.Box(-0.5f * l, 0.5f * l - 0.85f, 1.05f, h, -half_w, half_w, m.paint);
  p.Box(0.5f * l - 0.85f, 0.5f * l - 0.3f, 1.05f, h - 0.12f, -half_w + 0.05f, half_w - 0.05f,
        m.glass);
  const float r = static_cast<float>(rng.Uniform(0.33, 0.37));
  for (float x : {-0.5f * l + 0.9f, 0.5f * l - 0.9f}) {
    for (float z : {-0.5f * w + 0.11f, 0.5f * w - 0.11f}) p.Wheel(x, z, r, 0.22f, m.tyre);
  }
}

void BuildTruck(Parts& p, float l, float w, float h, const VehicleMaterials& m,
                int cargo_material) {
  const float half_w = 0.5f * w;
  const float cab_h = std::min(h, 3.0f);
  p.Box(0.5f * l - 2.2f, 0.5f * l - 0.03f, 0.55f, cab_h, -half_w + 0.05f, half_w - 0.05f, m.paint);
  p.Box(0.5f * l - 0.3f, 0.5f * l, 1.6f, cab_h - 0.3f, -half_w + 0.15f, half_w - 0.15f, m.glass);
  p.Box(-0.5f * l, 0.5f * l - 2.4f, 1.0f, h, -half_w, half_w, cargo_material);
  p.Box(-0.5f * l + 0.4f, 0.5f * l - 0.2f, 0.5f, 1.0f, -half_w + 0.45f, half_w - 0.45f, m.dark);
  const float r = 0.5f;
  std::vector<float> axles = {0.5f * l - 1.3f, -0.5f * l + 1.1f};
  if (l > 7.5f) axles.push_back(-0.5f * l + 2.5f);
  for (float x : axles) {
    for (float z : {-half_w + 0.18f, half_w - 0.18f}) p.Wheel(x, z, r, 0.32f, m.tyre);
  }
}

// Details of a person that are not clothes: shoes, hair, bags.
struct PersonMaterials {
  int top, bottom, skin, shoes, hair, bag;
};

// A walking or standing person: legs (a stride of up to a third of a metre, none when
// standing), arms (swinging against the legs, or hanging), torso, head with hair, shoes; some
// carry a backpack or a bag in one hand. The head's top is at h (the hair stays inside it).
void BuildPedestrian(Parts& p, float h, const PersonMaterials& m, Rng& rng) {
  const float s = h / 1.75f;
  const bool standing = rng.Bernoulli(0.2);
  const float stride = standing ? 0.0f : static_cast<float>(rng.Uniform(0.05, 0.33)) * s;
  const float swing = 0.6f * stride;
  const float lean = static_cast<float>(rng.Uniform(0.0, 0.05));
  const float hip = 0.5f * h, neck = 0.83f * h;
  const int carry = rng.Categorical({0.7, 0.18, 0.12});  // nothing, a backpack, a bag
  for (float side : {-1.0f, 1.0f}) {
    const Eigen::Vector3f foot(side * stride, 0.09f, 0.1f * s * side);
    p.Segment({0.0f, hip, 0.09f * s * side}, foot, 0.065f * s, 0.07f * s, m.bottom);
    p.Box(foot.x() - 0.05f * s, foot.x() + 0.17f * s, 0.0f, 0.09f, foot.z() - 0.05f * s,
          foot.z() + 0.05f * s, m.shoes);
    const Eigen::Vector3f hand(-side * swing, 0.44f * h, 0.24f * s * side);
    p.Segment({lean, neck - 0.03f * s, 0.21f * s * side}, hand, 0.045f * s, 0.045f * s, m.top);
    if (carry == 2 && side > 0.0f) {  // a bag hanging from the right hand
      p.Box(hand.x() - 0.17f * s, hand.x() + 0.17f * s, hand.y() - 0.3f * s, hand.y() - 0.02f,
            hand.z() - 0.05f * s, hand.z() + 0.05f * s, m.bag);
    }
  }
  p.Segment({0.0f, hip - 0.05f * s, 0.0f}, {lean, neck, 0.0f}, 0.11f * s, 0.18f * s, m.top);
  if (carry == 1) {  // a backpack on the back (local -x)
    p.Box(lean * 0.5f - 0.3f * s, lean * 0.5f - 0.1f * s, 0.6f * h, 0.8f * h, -0.15f * s, 0.15f * s,
          m.bag);
  }
  const Eigen::Vector3f head(lean + 0.01f, h - 0.115f * s, 0.0f);
  const Eigen::Vector3f head_r = Eigen::Vector3f(0.1f, 0.115f, 0.09f) * s;
  p.Ellipsoid(head, head_r, m.skin);
  // Hair: a cap over the back and top of the head, as high as the head.
  p.Ellipsoid(head + Eigen::Vector3f(-0.015f * s, 0.0f, 0.0f),
              Eigen::Vector3f(0.95f * head_r.x(), head_r.y(), 1.04f * head_r.z()), m.hair);
}

void BuildPersonSitting(Parts& p, float h, int top, int bottom, int skin, int hair) {
  const float s = h / 1.27f;
  const float seat = 0.46f * s;
  for (float side : {-1.0f, 1.0f}) {
    p.Segment({-0.05f, seat, 0.1f * side * s}, {0.4f * s, seat, 0.1f * side * s}, 0.07f * s,
              0.07f * s, bottom);
    p.Segment({0.4f * s, seat, 0.1f * side * s}, {0.45f * s, 0.02f, 0.11f * side * s}, 0.06f * s,
              0.06f * s, bottom);
    p.Segment({-0.08f * s, 0.98f * s, 0.2f * side * s},
              {0.25f * s, seat + 0.08f * s, 0.18f * side * s}, 0.045f * s, 0.045f * s, top);
  }
  p.Segment({-0.1f * s, seat - 0.05f * s, 0.0f}, {-0.12f * s, 1.02f * s, 0.0f}, 0.11f * s,
            0.18f * s, top);
  p.Ellipsoid({-0.11f * s, h - 0.115f * s, 0.0f}, Eigen::Vector3f(0.1f, 0.115f, 0.09f) * s, skin);
  p.Ellipsoid({-0.125f * s, h - 0.115f * s, 0.0f}, Eigen::Vector3f(0.095f, 0.115f, 0.094f) * s,
              hair);
}

void BuildCyclist(Parts& p, float h, int top, int bottom, int skin, int frame, int tyre, int helmet,
                  Rng& rng) {
  const float s = h / 1.72f;
  const float r = 0.34f;
  for (float x : {-0.53f, 0.53f}) p.Wheel(x * s, 0.0f, r, 0.045f, tyre);
  const Eigen::Vector3f bb(0.0f, 0.3f, 0.0f), saddle(-0.16f * s, 0.88f * s, 0.0f),
      head_tube(0.42f * s, 0.82f * s, 0.0f), bar(0.4f * s, 1.0f * s, 0.0f);
  p.Segment(bb, saddle, 0.02f, 0.02f, frame);
  p.Segment(saddle, head_tube, 0.02f, 0.02f, frame);
  p.Segment(bb, head_tube, 0.025f, 0.025f, frame);
  p.Segment(head_tube, {0.53f * s, r, 0.0f}, 0.02f, 0.02f, frame);
  p.Segment(bb, {-0.53f * s, r, 0.0f}, 0.02f, 0.02f, frame);
  p.Segment({0.4f * s, 1.0f * s, -0.26f * s}, {0.4f * s, 1.0f * s, 0.26f * s}, 0.02f, 0.02f, frame);
  const float phase = static_cast<float>(rng.Uniform(0.0, 2.0 * M_PI));
  const Eigen::Vector3f hip(-0.14f * s, 0.93f * s, 0.0f);
  const Eigen::Vector3f shoulder(0.2f * s, 1.43f * s, 0.0f);
  for (float side : {-1.0f, 1.0f}) {
    const float a = phase + (side > 0 ? 0.0f : static_cast<float>(M_PI));
    const Eigen::Vector3f pedal(0.17f * std::cos(a), 0.3f + 0.17f * std::sin(a), 0.1f * side);
    p.Segment(hip + Eigen::Vector3f(0, 0, 0.09f * side), pedal, 0.06f * s, 0.065f * s, bottom);
    p.Segment(shoulder + Eigen::Vector3f(0, 0, 0.2f * side * s),
              {0.4f * s, 1.0f * s, 0.24f * side * s}, 0.04f * s, 0.04f * s, top);
  }
  p.Segment(hip, shoulder, 0.11f * s, 0.18f * s, top);
  p.Ellipsoid({0.3f * s, h - 0.11f * s, 0.0f}, Eigen::Vector3f(0.11f, 0.11f, 0.09f) * s, skin);
  // A helmet (or hair) over the top and back of the head, no higher than the head.
  p.Ellipsoid({0.29f * s, h - 0.11f * s, 0.0f}, Eigen::Vector3f(0.1f, 0.11f, 0.097f) * s, helmet);
}

// Extent of parts in their local frame.
Aabb LocalBounds(const std::vector<Primitive>& parts) {
  Aabb b;
  for (const Primitive& p : parts) b.Extend(p.Bounds());
  return b;
}

// Moves the parts so that they are centred on the local origin in x and z and rest on the ground,
// places them at `location` (bottom centre) turned by `rotation_y`, and appends them to the scene
// as object `type`. The label box is the parts' extent (rounded to 0.01 m) at the given pose.
int EmitObject(Scene& scene, const std::string& type, Parts& parts, const Eigen::Vector3d& location,
               double rotation_y) {
  const Aabb local = LocalBounds(parts.parts());
  const Eigen::Vector3f shift(-0.5f * (local.min.x() + local.max.x()), -local.max.y(),
                              -0.5f * (local.min.z() + local.max.z()));
  const Eigen::Matrix3f rot = RotationY(static_cast<float>(rotation_y));
  const Eigen::Vector3f loc = location.cast<float>();
  SceneObject object;
  object.type = type;
  object.box.l = Round2(local.max.x() - local.min.x());
  object.box.h = Round2(local.max.y() - local.min.y());
  object.box.w = Round2(local.max.z() - local.min.z());
  object.box.location = location;
  object.box.rotation_y = rotation_y;
  object.first_primitive = static_cast<int>(scene.primitives.size());
  object.num_primitives = static_cast<int>(parts.parts().size());
  const int index = static_cast<int>(scene.objects.size());
  for (Primitive p : parts.parts()) {
    p.centre = loc + rot * (p.centre + shift);
    p.world_from_local = rot * p.world_from_local;
    p.object = index;
    scene.primitives.push_back(p);
  }
  scene.objects.push_back(object);
  return index;
}

}  // namespace

int AddObject(Scene& scene, const std::string& type, const Box3D& box, Rng& rng) {
  Parts parts;
  const float lf = static_cast<float>(box.l), wf = static_cast<float>(box.w),
              hf = static_cast<float>(box.h);
  if (type == "Car" || type == "Van" || type == "Truck" || type == "Misc" || type == "Tram") {
    const VehicleMaterials m = AddVehicleMaterials(scene, rng, CarColour(rng));
    if (type == "Car") {
      scene.materials[m.paint].scale_m = BuildCar(parts, lf, wf, hf, m, rng);
    } else if (type == "Van") {
      BuildVan(parts, lf, wf, hf, m, rng);
    } else if (type == "Truck") {
      const int cargo = scene.AddMaterial(MakeMaterial(
          Pattern::kPlain,
          Vary(rng, rng.Bernoulli(0.5) ? Rgb(0.7, 0.7, 0.68) : CarColour(rng), 0.1), 0.08f));
      BuildTruck(parts, lf, wf, hf, m, cargo);
    } else if (type == "Tram") {
      Material body = MakeMaterial(Pattern::kFacade, Vary(rng, Rgb(0.75, 0.72, 0.6), 0.1), 0.05f);
      body.albedo2 = Rgb(0.04, 0.05, 0.06);
      body.scale_m = 1.6f;
      const int body_m = scene.AddMaterial(body);
      parts.Box(-0.5f * lf, 0.5f * lf, 0.45f, hf - 0.35f, -0.5f * wf, 0.5f * wf, body_m);
      parts.Box(-0.25f * lf, 0.25f * lf, hf - 0.35f, hf, -0.3f * wf, 0.3f * wf, m.dark);
      for (float x : {-0.33f * lf, 0.0f, 0.33f * lf}) {
        parts.Box(x - 1.0f, x + 1.0f, 0.0f, 0.45f, -0.4f * wf, 0.4f * wf, m.dark);
      }
    } else {  // Misc: a trailer on one axle with a drawbar
      parts.Box(-0.5f * lf, 0.5f * lf - 0.8f, 0.45f, hf, -0.5f * wf, 0.5f * wf, m.paint);
      parts.Box(0.5f * lf - 0.8f, 0.5f * lf, 0.35f, 0.45f, -0.05f, 0.05f, m.dark);
      for (float z : {-0.5f * wf + 0.1f, 0.5f * wf - 0.1f})
        parts.Wheel(-0.1f * lf, z, 0.3f, 0.18f, m.tyre);
    }
  } else {
    const int top = scene.AddMaterial(ClothMaterial(rng, false));
    const int bottom = scene.AddMaterial(ClothMaterial(rng, true));
    const int skin =
        scene.AddMaterial(MakeMaterial(Pattern::kPlain, Vary(rng, Rgb(0.55, 0.4, 0.3), 0.3), 0.1f));
    // Hair: black, brown, blond or grey.
    const Eigen::Vector3f hair_colour = std::vector<Eigen::Vector3f>{
        Rgb(0.02, 0.018, 0.015), Rgb(0.08, 0.05, 0.03), Rgb(0.35, 0.27, 0.15),
        Rgb(0.35, 0.35, 0.35)}[rng.Categorical({0.3, 0.4, 0.15, 0.15})];
    const int hair = scene.AddMaterial(MakeMaterial(Pattern::kCloth, hair_colour, 0.3f));
    if (type == "Pedestrian") {
      PersonMaterials m{top, bottom, skin, 0, hair, 0};
      m.shoes = scene.AddMaterial(
          MakeMaterial(Pattern::kPlain, Vary(rng, Rgb(0.05, 0.045, 0.04), 0.5), 0.2f));
      m.bag = scene.AddMaterial(ClothMaterial(rng, false));
      BuildPedestrian(parts, hf, m, rng);
    } else if (type == "Person_sitting") {
      BuildPersonSitting(parts, hf, top, bottom, skin, hair);
    } else if (type == "Cyclist") {
      const int frame = scene.AddMaterial(MakeMaterial(Pattern::kPlain, CarColour(rng), 0.1f));
      const int tyre =
          scene.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.03, 0.03, 0.03), 0.1f, 0.04f));
      const int helmet =
          rng.Bernoulli(0.6)
              ? scene.AddMaterial(MakeMaterial(Pattern::kPlain, CarColour(rng), 0.1f))
              : hair;
      BuildCyclist(parts, hf, top, bottom, skin, frame, tyre, helmet, rng);
    } else {
      STEREODET_THROW_ARG() << "unknown synthetic object type '" << type << "'";
    }
  }
  return EmitObject(scene, type, parts, box.location, box.rotation_y);
}

int AddSimpleObject(Scene& scene, const std::string& type, const Box3D& box, uint64_t seed) {
  Rng rng(seed);
  return AddObject(scene, type, box, rng);
}

}  // namespace stereodet
