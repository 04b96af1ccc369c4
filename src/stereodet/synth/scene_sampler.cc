#include "stereodet/synth/scene_sampler.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "stereodet/synth/clutter.h"
#include "stereodet/synth/materials.h"
#include "stereodet/synth/objects.h"
#include "stereodet/synth/random.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

enum class StreetKind { kCity, kResidential, kRoad };

// Sizes (l, w, h) by class, after KITTI's means and spreads.
struct Dims {
  double l, w, h;
};
Dims SampleDims(const std::string& type, Rng& rng) {
  if (type == "Car") {
    switch (rng.Categorical({0.3, 0.5, 0.2})) {
      case 0:
        return {rng.Uniform(3.4, 3.9), rng.Uniform(1.55, 1.7), rng.Uniform(1.4, 1.55)};
      case 1:
        return {rng.Uniform(3.9, 4.5), rng.Uniform(1.6, 1.8), rng.Uniform(1.4, 1.55)};
      default:
        return {rng.Uniform(4.4, 4.95), rng.Uniform(1.75, 1.95), rng.Uniform(1.5, 1.75)};
    }
  }
  if (type == "Van") return {rng.Uniform(4.6, 5.8), rng.Uniform(1.85, 2.05), rng.Uniform(1.9, 2.5)};
  if (type == "Truck")
    return {rng.Uniform(6.5, 12.0), rng.Uniform(2.4, 2.55), rng.Uniform(2.9, 3.8)};
  if (type == "Tram")
    return {rng.Uniform(15.0, 28.0), rng.Uniform(2.5, 2.65), rng.Uniform(3.3, 3.6)};
  if (type == "Misc") return {rng.Uniform(2.5, 4.0), rng.Uniform(1.5, 2.0), rng.Uniform(1.2, 2.2)};
  // People around KITTI's class means (h 1.76 m for pedestrians, 1.74 m for cyclists, the means
  // 3D detectors use as size anchors), with a wider spread and a few children.
  if (type == "Pedestrian") {
    const bool child = rng.Bernoulli(0.05);
    const double h = child ? rng.Uniform(1.0, 1.45) : rng.ClampedNormal(1.76, 0.11, 1.45, 2.05);
    return {0.0, 0.0, h};
  }
  if (type == "Person_sitting") return {0.0, 0.0, rng.ClampedNormal(1.27, 0.08, 1.05, 1.45)};
  return {0.0, 0.0, rng.ClampedNormal(1.74, 0.09, 1.45, 2.0)};  // Cyclist
}

// The box AddObject builds an object of size `d` into, at `location` turned by `rotation_y`.
Box3D LabelBox(const Dims& d, const Eigen::Vector3d& location, double rotation_y) {
  Box3D box;
  box.l = d.l, box.w = d.w, box.h = d.h;
  box.location = location;
  box.rotation_y = rotation_y;
  return box;
}

struct Footprint {
  double lateral, along, radius;
};

class StreetBuilder {
 public:
  // `shape_rng` draws the road's shape, so that the streets and traffic drawn from `rng` are those
  // of a straight, flat road but for what the shape excludes (junctions).
  StreetBuilder(Scene& scene, const SceneOptions& options, Rng& rng, Rng& shape_rng)
      : scene_(scene), options_(options), rng_(rng), shape_rng_(shape_rng) {}

  void Build();

 private:
  // World position of road coordinates on a surface `height_m` above the ground.
  Eigen::Vector3d At(double lateral, double along, double height_m = 0.0) const {
    const Eigen::Vector2f xz =
        scene_.road.FromRoad(static_cast<float>(lateral), static_cast<float>(along));
    return {Round2(xz.x()), Round2(scene_.GroundY(xz.x(), xz.y()) - height_m), Round2(xz.y())};
  }
  // A heading relative to the road's at `along`, as a rotation_y.
  double Yaw(double relative, double along) const {
    return Round2(WrapYaw(Heading(along) + relative));
  }
  double Heading(double along) const { return scene_.road.ForwardYawAt(static_cast<float>(along)); }
  // Whether `along` lies within `margin` of a side street opening on `side` (0 left, 1 right).
  bool InJunction(double along, int side, double margin) const {
    for (const SideStreet& j : scene_.road.side_streets) {
      if (j.OnSide(side) && std::abs(along - j.along_m) <= j.half_width_m + margin) return true;
    }
    return false;
  }
  // [a0, a1] less the side streets on `side` (widened by `margin`); all of it for side -1.
  std::vector<std::pair<double, double>> OpenIntervals(double a0, double a1, int side,
                                                       double margin) const {
    std::vector<std::pair<double, double>> out{{a0, a1}};
    if (side < 0) return out;
    for (const SideStreet& j : scene_.road.side_streets) {
      if (!j.OnSide(side)) continue;
      const double c0 = j.along_m - j.half_width_m - margin,
                   c1 = j.along_m + j.half_width_m + margin;
      std::vector<std::pair<double, double>> next;
      for (const auto& [b0, b1] : out) {
        if (c1 <= b0 || c0 >= b1) {
          next.push_back({b0, b1});
          continue;
        }
        if (c0 - b0 > 0.5) next.push_back({b0, c0});
        if (b1 - c1 > 0.5) next.push_back({c1, b1});
      }
      out.swap(next);
    }
    return out;
  }
  static double WrapYaw(double a) {
    while (a >= M_PI) a -= 2.0 * M_PI;
    while (a < -M_PI) a += 2.0 * M_PI;
    return a;
  }
  // Background box aligned with the road: along [a0, a1], lateral [s0, s1], heights [h0, h1]
  // above the ground; with `side` >= 0 not across that side's side streets (widened by `margin`).
  // Long boxes (sidewalks, walls) are cut into pieces of at most kPieceM along the road: a BVH
  // over 200 m long boxes would make every ray visit them. The texture runs on across the cuts.
  void RoadBox(double a0, double a1, double s0, double s1, double h0, double h1, int material,
               int side = -1, double margin = 0.0) {
    const float u_offset = static_cast<float>(rng_.Uniform(0, 100));
    const float v_offset = static_cast<float>(rng_.Uniform(0, 3));
    for (const auto& [b0, b1] : OpenIntervals(a0, a1, side, margin)) {
      RoadBoxPieces(b0, b1, s0, s1, h0, h1, material, u_offset + static_cast<float>(b0 - a0),
                    v_offset);
    }
  }
  void RoadBoxPieces(double a0, double a1, double s0, double s1, double h0, double h1, int material,
                     float u_offset, float v_offset) {
    constexpr double kPieceM = 12.0;
    const int pieces = std::max(1, static_cast<int>(std::ceil((a1 - a0) / kPieceM)));
    const double step = (a1 - a0) / pieces;
    if (scene_.road.curvature_per_m != 0.0f || !scene_.ground.Flat()) {
      for (int i = 0; i < pieces; ++i) {
        ShapedPiece(a0 + i * step, a0 + (i + 1) * step, s0, s1, h0, h1, material,
                    u_offset + static_cast<float>((i + 0.5) * step), v_offset);
      }
      return;
    }
    for (int i = 0; i < pieces; ++i) {
      const double b0 = a0 + i * step, b1 = b0 + step;
      const Eigen::Vector2f c = scene_.road.FromRoad(static_cast<float>(0.5 * (s0 + s1)),
                                                     static_cast<float>(0.5 * (b0 + b1)));
      Primitive p = MakeBox(
          Eigen::Vector3f(c.x(), scene_.ground_y_m - static_cast<float>(0.5 * (h0 + h1)), c.y()),
          Eigen::Vector3f(static_cast<float>(0.5 * step), static_cast<float>(0.5 * (h1 - h0)),
                          static_cast<float>(0.5 * (s1 - s0))),
          RotationY(scene_.road.ForwardYaw()), material);
      p.texture_offset =
          Eigen::Vector2f(u_offset + static_cast<float>(0.5 * (b0 + b1) - a0), v_offset);
      scene_.primitives.push_back(p);
    }
  }
  // One piece of a RoadBox on a bending or shaped road: a box along the chord of its centre line,
  // tilted to the ground (the chord's slope along the road, the ground's normal across it), a
  // little longer than the chord where the road bends so that neighbours close up at the outer
  // edge, reaching 0.5 m into the ground when it stands on it (h0 = 0).
  void ShapedPiece(double b0, double b1, double s0, double s1, double h0, double h1, int material,
                   float u_centre, float v_offset) {
    const double sc = 0.5 * (s0 + s1), half_width = 0.5 * (s1 - s0);
    const auto surface = [&](double along) {
      const Eigen::Vector2f xz =
          scene_.road.FromRoad(static_cast<float>(sc), static_cast<float>(along));
      return Eigen::Vector3d(xz.x(), scene_.GroundY(xz.x(), xz.y()), xz.y());
    };
    const Eigen::Vector3d p0 = surface(b0), p1 = surface(b1), mid = 0.5 * (p0 + p1);
    const Eigen::Vector3d ex = (p1 - p0).normalized();
    const Eigen::Vector3d up = scene_.ground.Normal(mid.x(), mid.z()).cast<double>();
    const Eigen::Vector3d ez = ex.cross(-up).normalized();
    const Eigen::Vector3d ey = ez.cross(ex);
    Eigen::Matrix3f rotation;
    rotation.col(0) = ex.cast<float>(), rotation.col(1) = ey.cast<float>(),
    rotation.col(2) = ez.cast<float>();
    const double bottom = h0 == 0.0 ? -0.5 : h0;
    const double half_length =
        0.5 * (p1 - p0).norm() +
        0.5 * std::abs(scene_.road.curvature_per_m) * (b1 - b0) * half_width + 0.01;
    const Eigen::Vector3d centre = mid - 0.5 * (bottom + h1) * ey;
    Primitive p = MakeBox(
        centre.cast<float>(),
        Eigen::Vector3f(static_cast<float>(half_length), static_cast<float>(0.5 * (h1 - bottom)),
                        static_cast<float>(half_width)),
        rotation, material);
    p.texture_offset = Eigen::Vector2f(u_centre, v_offset);
    scene_.primitives.push_back(p);
  }
  bool Free(double lateral, double along, double radius) const {
    for (const Footprint& f : taken_) {
      if (std::hypot(f.lateral - lateral, f.along - along) < f.radius + radius) return false;
    }
    // The ego car.
    return !(std::abs(lateral - ego_lateral_) < 1.3 + radius && along > -3.5 - radius &&
             along < 2.0 + radius);
  }
  void Take(double lateral, double along, double radius) {
    taken_.push_back({lateral, along, radius});
  }

  std::string VehicleType(bool parked) {
    if (parked)
      return std::vector<std::string>{"Car", "Van", "Truck",
                                      "Misc"}[rng_.Categorical({0.89, 0.08, 0.015, 0.015})];
    return std::vector<std::string>{"Car", "Van", "Truck"}[rng_.Categorical({0.86, 0.08, 0.06})];
  }
  // Places a vehicle centred at (lateral, along) heading along the road (or against it).
  double PlaceVehicle(const std::string& type, double lateral, double along, bool oncoming,
                      double yaw_sd, double min_rear_along = -1e9) {
    return PlaceVehicleTurned(type, lateral, along, oncoming ? M_PI : 0.0, yaw_sd, min_rear_along);
  }
  // ... heading `relative_yaw` from the road's heading there.
  double PlaceVehicleTurned(const std::string& type, double lateral, double along,
                            double relative_yaw, double yaw_sd, double min_rear_along = -1e9) {
    const Dims d = SampleDims(type, rng_);
    // `along` is the centre; a long vehicle placed just ahead would reach back past the ego car's
    // bumper, so the caller may ask for its rear to stay ahead of a point.
    along = std::max(along, min_rear_along + 0.5 * d.l);
    const double yaw = Yaw(relative_yaw + rng_.Normal(0.0, yaw_sd), along);
    Take(lateral, along, 0.5 * d.l);
    AddObject(scene_, type, LabelBox(d, At(lateral, along), yaw), rng_);
    return d.l;
  }
  void PlacePerson(const std::string& type, double lateral, double along, double height_m,
                   double yaw) {
    const Dims d = SampleDims(type, rng_);
    Take(lateral, along, type == "Cyclist" ? 0.9 : 0.4);
    AddObject(scene_, type,
              LabelBox({0, 0, d.h}, At(lateral, along, height_m), Round2(WrapYaw(yaw))), rng_);
  }

  void Materials();
  void Lanes();
  void RoadShape();
  void JunctionTraffic();
  void Traffic();
  void Trams();
  void Parking(double lateral, double width, int side);
  void Sidewalk(int side);
  void Roadside(int side);
  void Pedestrians();
  void StreetFurniture(int side, Rng& rng);

  Scene& scene_;
  const SceneOptions& options_;
  Rng& rng_;
  Rng& shape_rng_;
  StreetKind kind_ = StreetKind::kCity;
  std::vector<Footprint> taken_;
  double ego_lateral_ = 0.0;
  // Lateral layout (metres to the right of road coordinate 0).
  struct Lane {
    double centre;
    bool oncoming;
  };
  std::vector<Lane> lanes_;
  double lane_width_ = 3.3;
  double carriage_left_ = 0.0, carriage_right_ = 0.0;  // edges of the driving lanes
  double parking_width_[2] = {0.0, 0.0};               // left, right
  double sidewalk_inner_[2] = {0.0, 0.0}, sidewalk_outer_[2] = {0.0, 0.0};
  double curb_height_ = 0.12;
  // Materials.
  int sidewalk_material_ = 0, curb_material_ = 0, grass_material_ = 0, foliage_material_ = 0,
      bark_material_ = 0, metal_material_ = 0, wall_material_ = 0, fence_material_ = 0;
};

void StreetBuilder::Materials() {
  Material asphalt =
      MakeMaterial(Pattern::kAsphalt, Vary(rng_, Rgb(0.15, 0.15, 0.155), 0.25), 0.75f, 0.22f);
  asphalt.albedo2 = Rgb(0.7, 0.7, 0.68);
  scene_.road_material = scene_.AddMaterial(asphalt);
  Material offroad =
      kind_ == StreetKind::kCity
          ? MakeMaterial(Pattern::kPaving, Vary(rng_, Rgb(0.3, 0.29, 0.27), 0.2), 0.45f)
          : MakeMaterial(Pattern::kGrass, Vary(rng_, Rgb(0.12, 0.2, 0.06), 0.3), 0.45f, 0.5f);
  offroad.albedo2 = kind_ == StreetKind::kCity ? Rgb(0.1, 0.1, 0.1) : Rgb(0.22, 0.18, 0.1);
  offroad.scale_m = 0.5f;
  scene_.offroad_material = scene_.AddMaterial(offroad);
  Material paving = MakeMaterial(Pattern::kPaving, Vary(rng_, Rgb(0.35, 0.33, 0.31), 0.2), 0.45f);
  paving.albedo2 = Rgb(0.12, 0.12, 0.11);
  paving.scale_m = static_cast<float>(rng_.Uniform(0.25, 0.5));
  sidewalk_material_ = scene_.AddMaterial(paving);
  // Kerb stones: 1 m blocks with joints and weathered grain.
  Material curb = MakeMaterial(Pattern::kPaving, Vary(rng_, Rgb(0.42, 0.42, 0.4), 0.1), 0.35f);
  curb.albedo2 = Rgb(0.15, 0.15, 0.14);
  curb.scale_m = 1.0f;
  curb_material_ = scene_.AddMaterial(curb);
  Material grass = MakeMaterial(Pattern::kGrass, Vary(rng_, Rgb(0.1, 0.2, 0.05), 0.3), 0.5f, 0.5f);
  grass.albedo2 = Rgb(0.2, 0.17, 0.1);
  grass_material_ = scene_.AddMaterial(grass);
  Material foliage =
      MakeMaterial(Pattern::kFoliage, Vary(rng_, Rgb(0.06, 0.14, 0.04), 0.3), 0.7f, 0.55f);
  foliage.albedo2 = Vary(rng_, Rgb(0.14, 0.2, 0.06), 0.3);
  foliage_material_ = scene_.AddMaterial(foliage);
  bark_material_ = scene_.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.12, 0.09, 0.07), 0.4f));
  metal_material_ = scene_.AddMaterial(MakeMaterial(Pattern::kPlain, Rgb(0.3, 0.31, 0.32), 0.1f));
  Material brick = MakeMaterial(Pattern::kBrick, Vary(rng_, Rgb(0.4, 0.2, 0.13), 0.2), 0.2f);
  brick.albedo2 = Rgb(0.5, 0.48, 0.45);
  if (rng_.Bernoulli(0.4)) {
    brick = MakeMaterial(Pattern::kPlain, Vary(rng_, Rgb(0.45, 0.43, 0.4), 0.25), 0.35f);
  }
  wall_material_ = scene_.AddMaterial(brick);
  Material fence = MakeMaterial(Pattern::kFence, Vary(rng_, Rgb(0.3, 0.22, 0.15), 0.4), 0.3f);
  fence.albedo2 = Rgb(0.05, 0.07, 0.04);
  fence.scale_m = static_cast<float>(rng_.Uniform(0.1, 0.2));
  fence_material_ = scene_.AddMaterial(fence);
}

void StreetBuilder::Lanes() {
  lane_width_ = rng_.Uniform(3.0, 3.6);
  int forward_lanes = 1, oncoming_lanes = 1;
  switch (kind_) {
    case StreetKind::kCity:
      forward_lanes = rng_.Categorical({0.6, 0.4}) + 1;
      oncoming_lanes = rng_.Categorical({0.15, 0.55, 0.3});
      break;
    case StreetKind::kResidential:
      forward_lanes = 1;
      oncoming_lanes = rng_.Categorical({0.2, 0.8});
      break;
    case StreetKind::kRoad:
      forward_lanes = rng_.Categorical({0.5, 0.5}) + 1;
      oncoming_lanes = rng_.Categorical({0.1, 0.5, 0.4});
      break;
  }
  // Lanes from left to right; the ego car drives in one of the forward lanes.
  const int ego = oncoming_lanes + rng_.UniformInt(0, forward_lanes - 1);
  const int total = forward_lanes + oncoming_lanes;
  for (int i = 0; i < total; ++i) lanes_.push_back({(i - ego) * lane_width_, i < oncoming_lanes});
  carriage_left_ = lanes_.front().centre - 0.5 * lane_width_;
  carriage_right_ = lanes_.back().centre + 0.5 * lane_width_;
  // Markings: lane lines (dashed between lanes of one direction, solid or dashed between the two
  // directions), edge lines where there is no parking.
  for (int i = 1; i < total; ++i) {
    const bool divider = lanes_[i - 1].oncoming != lanes_[i].oncoming;
    scene_.road.markings.push_back({static_cast<float>(lanes_[i].centre - 0.5 * lane_width_),
                                    divider ? 0.15f : 0.12f, !divider || rng_.Bernoulli(0.5)});
  }
  const double parking_p =
      kind_ == StreetKind::kCity ? 0.85 : (kind_ == StreetKind::kResidential ? 0.6 : 0.0);
  for (int side = 0; side < 2; ++side) {
    parking_width_[side] =
        rng_.Bernoulli(parking_p) ? rng_.Uniform(2.0, 2.5) : rng_.Uniform(0.3, 0.8);
    const double edge = side == 0 ? carriage_left_ : carriage_right_;
    if (parking_width_[side] > 1.5 || rng_.Bernoulli(0.5)) {
      scene_.road.markings.push_back(
          {static_cast<float>(edge + (side == 0 ? 0.15 : -0.15)), 0.12f, false});
    }
  }
  scene_.road.left_edge_m = static_cast<float>(carriage_left_ - parking_width_[0]);
  scene_.road.right_edge_m = static_cast<float>(carriage_right_ + parking_width_[1]);
}

void StreetBuilder::RoadShape() {
  if (!options_.road_shapes) return;
  Rng& rng = shape_rng_;
  const auto log_uniform = [&](double lo, double hi) {
    return std::exp(rng.Uniform(std::log(lo), std::log(hi)));
  };
  // Draws in a fixed order, each used or not.
  const bool bend = rng.Bernoulli(options_.bend_fraction);
  const double bend_radius = log_uniform(options_.min_bend_radius_m, options_.max_bend_radius_m);
  const double bend_sign = rng.Bernoulli(0.5) ? 1.0 : -1.0;
  const bool vertical = rng.Bernoulli(options_.vertical_curve_fraction);
  const double grade_change = rng.Uniform(0.02, std::max(0.02, options_.max_grade_change));
  const double vertical_radius =
      log_uniform(options_.min_vertical_radius_m, options_.max_vertical_radius_m);
  const double vertical_sign = rng.Bernoulli(0.5) ? 1.0 : -1.0;
  const double vertical_centre = rng.Uniform(0.0, 80.0);
  const bool crowned = rng.Bernoulli(options_.crown_fraction);
  const double crossfall = rng.Uniform(0.01, std::max(0.01, options_.max_crossfall));
  const double pitch = rng.Normal(0.0, options_.pitch_sd_deg * M_PI / 180.0);
  const double roll = rng.Normal(0.0, options_.roll_sd_deg * M_PI / 180.0);
  const bool junction = rng.Bernoulli(options_.side_street_fraction);
  const double junction_along = rng.Uniform(12.0, 70.0);
  const double junction_half_width = rng.Uniform(3.0, 5.0);
  const int junction_sides = rng.Categorical({0.3, 0.3, 0.4});

  Road& road = scene_.road;
  if (bend) road.curvature_per_m = static_cast<float>(bend_sign / bend_radius);
  GroundProfile& g = scene_.ground;
  // The profile's frame: the camera's point on the ground, the road's heading there.
  g.origin_xz = Eigen::Vector2d::Zero();
  g.forward_xz = road.forward_xz.cast<double>();
  g.pitch = std::tan(pitch);
  g.roll = std::tan(roll);
  if (vertical) {
    g.vertical_curvature_per_m = vertical_sign / vertical_radius;
    g.vertical_half_length_m = 0.5 * grade_change * vertical_radius;
    g.vertical_centre_m = vertical_centre;
  }
  if (crowned) {
    // The crown: the line between the two directions (the middle of a one-way carriageway), in
    // the profile's frame, whose lateral 0 is the camera's (road lateral ego_lateral_).
    double crown = 0.5 * (carriage_left_ + carriage_right_);
    for (size_t i = 1; i < lanes_.size(); ++i) {
      if (lanes_[i - 1].oncoming != lanes_[i].oncoming)
        crown = lanes_[i].centre - 0.5 * lane_width_;
    }
    const double half = std::max(1.5, std::max(crown - carriage_left_, carriage_right_ - crown));
    g.crown_lateral_m = crown - ego_lateral_;
    g.crown_half_width_m = half;
    g.crown_curvature_per_m = -crossfall / half;
  }
  if (junction) {
    SideStreet j;
    j.along_m = static_cast<float>(Round2(junction_along));
    j.half_width_m = static_cast<float>(Round2(junction_half_width));
    j.left = junction_sides != 1;
    j.right = junction_sides != 0;
    road.side_streets.push_back(j);
  }
}

void StreetBuilder::JunctionTraffic() {
  // Vehicles in the side streets, waiting to turn into the road or leaving it; they drive on the
  // right of the side street.
  for (const SideStreet& j : scene_.road.side_streets) {
    for (int side = 0; side < 2; ++side) {
      if (!j.OnSide(side)) continue;
      const double sign = side == 0 ? -1.0 : 1.0;
      for (int k = 0; k < 2; ++k) {
        if (!rng_.Bernoulli(0.45 * options_.object_density)) continue;
        const bool towards_road = rng_.Bernoulli(0.6);
        // Heading to the road's right (+pi/2) means driving on the side street's near (-along)
        // half.
        const bool heading_right = (side == 1) != towards_road;
        const double along = j.along_m + (heading_right ? -0.5 : 0.5) * j.half_width_m;
        const double edge = side == 0 ? scene_.road.left_edge_m : scene_.road.right_edge_m;
        const double lateral = edge + sign * (rng_.Uniform(3.0, 6.0) + 7.0 * k);
        const std::string type = VehicleType(false);
        if (!Free(lateral, along, 2.5)) continue;
        PlaceVehicleTurned(type, lateral, along, heading_right ? 0.5 * M_PI : -0.5 * M_PI, 0.05);
      }
    }
  }
}

void StreetBuilder::Traffic() {
  const double density = options_.object_density;
  for (const Lane& lane : lanes_) {
    const bool ego_lane = std::abs(lane.centre - ego_lateral_) < 0.5 * lane_width_;
    double along = options_.min_along_m + rng_.Uniform(0.0, 20.0);
    const double mean_gap = (kind_ == StreetKind::kRoad ? 40.0 : 55.0) / std::max(density, 1e-3);
    while (along < options_.max_along_m) {
      if (ego_lane && along > -8.0 && along < 6.0) {
        along = 6.0 + rng_.Uniform(0.0, 8.0);
        continue;
      }
      const std::string type = VehicleType(false);
      const double lateral = lane.centre + rng_.Normal(0.0, 0.2);
      if (Free(lateral, along, 3.0)) {
        // In the ego lane the vehicle ahead keeps its rear at least kEgoGapM ahead of the
        // camera (about 4 m from the ego car's bumper): version 4 placed its centre there, so a
        // truck's rear could reach the camera.
        constexpr double kEgoGapM = 6.0;
        const double l = PlaceVehicle(type, lateral, along, lane.oncoming, 0.03,
                                      ego_lane && along > -8.0 ? kEgoGapM : -1e9);
        along += l;
      }
      along += 4.0 + rng_.Uniform(0.0, 2.0 * mean_gap);
    }
  }
  // Cyclists ride along the right edge of the carriageway (or against it on the left).
  const double cyclists = (kind_ == StreetKind::kRoad ? 0.1 : 0.18) * density;
  for (int i = 0; i < 4; ++i) {
    if (!rng_.Bernoulli(cyclists / 4.0 * 2.0)) continue;
    const bool right = rng_.Bernoulli(0.7);
    const double lateral = right ? carriage_right_ - 0.6 : carriage_left_ + 0.6;
    const double along = rng_.Uniform(4.0, 50.0);
    if (!Free(lateral, along, 1.0)) continue;
    PlacePerson("Cyclist", lateral, along, 0.0,
                Heading(along) + (right ? 0.0 : M_PI) + rng_.Normal(0.0, 0.08));
  }
}

void StreetBuilder::Trams() {
  // A tram now and then on a city street, placed before the other vehicles so it finds room.
  if (kind_ != StreetKind::kCity || !rng_.Bernoulli(std::min(1.0, 0.2 * options_.object_density)))
    return;
  const Lane& lane = lanes_[rng_.UniformInt(0, static_cast<int>(lanes_.size()) - 1)];
  const double along = rng_.Uniform(20.0, 70.0);
  if (Free(lane.centre, along, 10.0)) PlaceVehicle("Tram", lane.centre, along, lane.oncoming, 0.01);
}

void StreetBuilder::Parking(double lateral, double width, int side) {
  if (width < 1.5) return;
  const double density = options_.object_density;
  const double fill =
      (kind_ == StreetKind::kCity ? rng_.Uniform(0.15, 0.5) : rng_.Uniform(0.1, 0.4)) *
      std::min(1.0, density);
  double along = options_.min_along_m + rng_.Uniform(0.0, 6.0);
  while (along < options_.max_along_m) {
    const double slot = rng_.Uniform(5.2, 6.5);
    if (rng_.Bernoulli(fill)) {
      const std::string type = VehicleType(true);
      const double l_guess = type == "Truck" ? 9.0 : 5.0;
      const double centre_along = along + 0.5 * l_guess;
      const double lat = lateral + (side == 0 ? 1 : -1) * rng_.Uniform(0.0, 0.25);
      if (Free(lat, centre_along, 2.2) && !InJunction(centre_along, side, 0.5 * l_guess + 0.5)) {
        const double l = PlaceVehicle(type, lat, centre_along, rng_.Bernoulli(0.25), 0.03);
        along += std::max(0.0, l - slot);
      }
    }
    along += slot;
  }
}

void StreetBuilder::Sidewalk(int side) {
  const double inner = side == 0 ? scene_.road.left_edge_m : scene_.road.right_edge_m;
  const double width = kind_ == StreetKind::kCity          ? rng_.Uniform(2.5, 5.0)
                       : kind_ == StreetKind::kResidential ? rng_.Uniform(1.5, 3.0)
                                                           : rng_.Uniform(0.0, 1.5);
  const double outer = side == 0 ? inner - width : inner + width;
  sidewalk_inner_[side] = inner;
  sidewalk_outer_[side] = outer;
  if (width < 0.5) return;
  const double s0 = std::min(inner, outer), s1 = std::max(inner, outer);
  const double a0 = options_.min_along_m - 20.0, a1 = options_.max_along_m + 100.0;
  RoadBox(a0, a1, s0, s1, 0.0, curb_height_, sidewalk_material_, side);
  // The kerb stone: a thin lighter strip at the road side.
  const double k0 = side == 0 ? inner - 0.15 : inner, k1 = side == 0 ? inner : inner + 0.15;
  RoadBox(a0, a1, k0, k1, 0.0, curb_height_ + 0.005, curb_material_, side);
}

void StreetBuilder::Roadside(int side) {
  const double sign = side == 0 ? -1.0 : 1.0;
  const double line = sidewalk_outer_[side];
  const double a0 = options_.min_along_m - 20.0, a1 = options_.max_along_m + 90.0;
  // Trees and poles along the kerb.
  const double tree_p =
      kind_ == StreetKind::kCity ? 0.4 : (kind_ == StreetKind::kResidential ? 0.7 : 0.5);
  if (rng_.Bernoulli(tree_p)) {
    const double spacing = rng_.Uniform(8.0, 20.0);
    for (double a = a0 + rng_.Uniform(0.0, spacing); a < a1;
         a += spacing * rng_.Uniform(0.8, 1.3)) {
      const double s = sidewalk_inner_[side] + sign * rng_.Uniform(0.6, 1.2);
      if (!Free(s, a, 1.0) || InJunction(a, side, 1.5)) continue;
      Take(s, a, 0.5);
      const double trunk_h = rng_.Uniform(2.0, 3.5), crown = rng_.Uniform(1.5, 3.2);
      const Eigen::Vector3d base = At(s, a, curb_height_);
      const float r = static_cast<float>(rng_.Uniform(0.1, 0.22));
      Primitive trunk = MakeCylinder(
          Eigen::Vector3f(base.x(), base.y() - 0.5 * (trunk_h + 0.5), base.z()), r,
          static_cast<float>(0.5 * (trunk_h + 0.5)), Eigen::Matrix3f::Identity(), bark_material_);
      scene_.primitives.push_back(trunk);
      Primitive top =
          MakeEllipsoid(Eigen::Vector3f(base.x(), base.y() - trunk_h - 0.8 * crown, base.z()),
                        Eigen::Vector3f(crown, 1.1 * crown, crown).cast<float>(),
                        RotationY(rng_.Uniform(0, 3)), foliage_material_);
      top.texture_offset = Eigen::Vector2f(static_cast<float>(rng_.Uniform(0, 50)), 0.0f);
      scene_.primitives.push_back(top);
    }
  }
  {
    const double spacing = rng_.Uniform(20.0, 40.0);
    for (double a = a0 + rng_.Uniform(0.0, spacing); a < a1; a += spacing) {
      const double s = sidewalk_inner_[side] + sign * 0.4;
      if (!Free(s, a, 0.3) || InJunction(a, side, 0.5)) continue;
      const double h = rng_.Uniform(4.0, 8.0);
      const Eigen::Vector3d base = At(s, a, curb_height_);
      scene_.primitives.push_back(
          MakeCylinder(Eigen::Vector3f(base.x(), base.y() - 0.5 * h, base.z()), 0.07f,
                       static_cast<float>(0.5 * h), Eigen::Matrix3f::Identity(), metal_material_));
      if (rng_.Bernoulli(0.5)) {  // a sign
        Primitive sign_box = MakeBox(
            Eigen::Vector3f(base.x(), base.y() - 2.4f, base.z()),
            Eigen::Vector3f(0.03f, 0.3f, 0.3f), RotationY(static_cast<float>(Heading(a))),
            scene_.AddMaterial(MakeMaterial(Pattern::kPlain, CarColour(rng_), 0.05f, 0.9f)));
        scene_.primitives.push_back(sign_box);
      }
    }
  }
  // Buildings, front yards, fences and hedges.
  double a = a0;
  while (a < a1) {
    if (kind_ == StreetKind::kCity) {
      const double w = rng_.Uniform(8.0, 28.0);
      const double setback = rng_.Bernoulli(0.8) ? 0.0 : rng_.Uniform(1.0, 6.0);
      const double depth = rng_.Uniform(10.0, 16.0), h = rng_.Uniform(9.0, 22.0);
      if (rng_.Bernoulli(0.1)) {  // a gap: a yard behind a 30 cm wall
        const double s0 = line + sign * 0.3, s1 = line + sign * 0.6;
        RoadBox(a, a + w, std::min(s0, s1), std::max(s0, s1), 0.0, rng_.Uniform(1.0, 2.5),
                wall_material_, side, 1.5);
      } else {
        Material facade = MakeMaterial(
            Pattern::kFacade,
            Vary(rng_,
                 std::vector<Eigen::Vector3f>{Rgb(0.6, 0.53, 0.42), Rgb(0.68, 0.66, 0.62),
                                              Rgb(0.45, 0.44, 0.43), Rgb(0.5, 0.3, 0.22),
                                              Rgb(0.65, 0.58, 0.38)}[rng_.UniformInt(0, 4)],
                 0.15),
            0.25f);
        facade.albedo2 = Vary(rng_, Rgb(0.06, 0.07, 0.09), 0.5);
        facade.scale_m = static_cast<float>(rng_.Uniform(2.4, 4.2));
        const double s_front = line + sign * setback;
        RoadBox(a, a + w, std::min(s_front, s_front + sign * depth),
                std::max(s_front, s_front + sign * depth), 0.0, h, scene_.AddMaterial(facade), side,
                1.5);
      }
      a += w + (rng_.Bernoulli(0.15) ? rng_.Uniform(2.0, 8.0) : 0.0);
    } else if (kind_ == StreetKind::kResidential) {
      const double w = rng_.Uniform(12.0, 25.0);
      // Fence, wall or hedge at the plot's front, a house set back behind it.
      const int front = rng_.Categorical({0.35, 0.25, 0.3, 0.1});
      const double s_front = line + sign * 0.2;
      const double fs0 = std::min(s_front, s_front + sign * (front == 2 ? 0.8 : 0.12));
      const double fs1 = std::max(s_front, s_front + sign * (front == 2 ? 0.8 : 0.12));
      if (front == 0)
        RoadBox(a, a + w - 0.5, fs0, fs1, 0.0, rng_.Uniform(0.9, 1.6), fence_material_, side, 1.5);
      if (front == 1)
        RoadBox(a, a + w - 0.5, fs0, fs1, 0.0, rng_.Uniform(0.6, 1.8), wall_material_, side, 1.5);
      if (front == 2)
        RoadBox(a, a + w - 0.5, fs0, fs1, 0.0, rng_.Uniform(1.0, 2.2), foliage_material_, side,
                1.5);
      if (rng_.Bernoulli(0.85)) {
        Material facade = MakeMaterial(
            Pattern::kFacade,
            Vary(rng_,
                 std::vector<Eigen::Vector3f>{Rgb(0.7, 0.66, 0.58), Rgb(0.62, 0.55, 0.45),
                                              Rgb(0.55, 0.35, 0.28),
                                              Rgb(0.7, 0.7, 0.68)}[rng_.UniformInt(0, 3)],
                 0.15),
            0.25f);
        facade.albedo2 = Vary(rng_, Rgb(0.06, 0.07, 0.09), 0.5);
        facade.scale_m = static_cast<float>(rng_.Uniform(2.8, 4.5));
        const double setback = rng_.Uniform(3.0, 10.0), depth = rng_.Uniform(8.0, 12.0);
        const double hw = std::min(w - 3.0, rng_.Uniform(8.0, 14.0));
        const double s_house = line + sign * setback;
        RoadBox(a + 1.5, a + 1.5 + hw, std::min(s_house, s_house + sign * depth),
                std::max(s_house, s_house + sign * depth), 0.0, rng_.Uniform(5.5, 10.0),
                scene_.AddMaterial(facade), side, 1.5);
      }
      a += w;
    } else {
      const double w = rng_.Uniform(20.0, 60.0);
      const int kind = rng_.Categorical({0.35, 0.25, 0.2, 0.2});
      const double s_front = line + sign * rng_.Uniform(0.5, 4.0);
      if (kind == 0) {  // a hedge or a wood's edge
        const double d = rng_.Uniform(1.0, 6.0);
        RoadBox(a, a + w, std::min(s_front, s_front + sign * d),
                std::max(s_front, s_front + sign * d), 0.0, rng_.Uniform(1.5, 7.0),
                foliage_material_, side, 1.5);
      } else if (kind == 1) {  // guard rail
        const double s = sidewalk_inner_[side] + sign * 0.5;
        RoadBox(a, a + w, std::min(s, s + sign * 0.08), std::max(s, s + sign * 0.08), 0.45, 0.75,
                metal_material_, side, 1.5);
      } else if (kind == 2) {  // a noise wall or fence
        // Named draws: the order in which function arguments are evaluated is unspecified.
        const double height = rng_.Uniform(1.5, 3.5);
        const int material = rng_.Bernoulli(0.5) ? wall_material_ : fence_material_;
        RoadBox(a, a + w, std::min(s_front, s_front + sign * 0.2),
                std::max(s_front, s_front + sign * 0.2), 0.0, height, material, side, 1.5);
      }
      a += w;
    }
  }
}

void StreetBuilder::Pedestrians() {
  const double density = options_.object_density;
  const double mean =
      (kind_ == StreetKind::kCity ? 2.1 : (kind_ == StreetKind::kResidential ? 0.8 : 0.15)) *
      density;
  // Groups of one to three walking along the sidewalks, sometimes across the road.
  int groups = 0;
  for (int i = 0; i < 12; ++i) groups += rng_.Bernoulli(mean / 12.0 / 1.5) ? 1 : 0;
  for (int g = 0; g < groups; ++g) {
    const int side = rng_.UniformInt(0, 1);
    const double sign = side == 0 ? -1.0 : 1.0;
    const bool crossing = rng_.Bernoulli(0.12);
    const double along = rng_.Uniform(4.0, 45.0);
    const double width = std::abs(sidewalk_outer_[side] - sidewalk_inner_[side]);
    double lateral, height, heading;
    if (crossing || width < 0.8) {
      lateral = rng_.Uniform(scene_.road.left_edge_m + 1.0, scene_.road.right_edge_m - 1.0);
      height = 0.0;
      heading = Heading(along) + (rng_.Bernoulli(0.5) ? 0.5 : -0.5) * M_PI;
      if (!crossing) continue;
    } else {
      lateral = sidewalk_inner_[side] + sign * rng_.Uniform(0.5, std::max(0.6, width - 0.4));
      height = curb_height_;
      heading = Heading(along) + (rng_.Bernoulli(0.5) ? 0.0 : M_PI);
    }
    const int size = rng_.Categorical({0.6, 0.3, 0.1}) + 1;
    for (int k = 0; k < size; ++k) {
      const double dl = k == 0 ? 0.0 : rng_.Uniform(-0.9, 0.9),
                   da = k == 0 ? 0.0 : rng_.Uniform(-1.5, 1.5);
      if (!Free(lateral + dl, along + da, 0.4)) continue;
      PlacePerson("Pedestrian", lateral + dl, along + da, height, heading + rng_.Normal(0.0, 0.3));
    }
  }
  // People sitting on a bench by the sidewalk (rare, as in KITTI).
  if (kind_ != StreetKind::kRoad && rng_.Bernoulli(0.06 * density)) {
    const int side = rng_.UniformInt(0, 1);
    const double sign = side == 0 ? -1.0 : 1.0;
    const double along = rng_.Uniform(6.0, 30.0);
    const double lateral = sidewalk_outer_[side] - sign * 0.6;
    if (Free(lateral, along, 1.5)) {
      // Facing the road.
      const double heading = Heading(along) + sign * 0.5 * M_PI;
      const int n = rng_.UniformInt(1, 2);
      for (int k = 0; k < n; ++k) {
        PlacePerson("Person_sitting", lateral, along + 0.7 * k, curb_height_, heading);
      }
      RoadBox(along - 0.7, along + 0.7 * n, lateral - 0.35, lateral + 0.35, 0.35, 0.45,
              bark_material_);
    }
  }
}

// Sign posts, street lamps, bins, bollards (sometimes in a row) and utility cabinets on the
// sidewalk of `side` (synth/clutter.h): near the kerb, cabinets also at the back of the sidewalk;
// on country roads only sign posts and bollards on the verge. Kept clear of the objects and
// trees already placed (Free), so they occlude what stands behind them without intersecting it.
void StreetBuilder::StreetFurniture(int side, Rng& rng) {
  const double sign = side == 0 ? -1.0 : 1.0;
  const double inner = sidewalk_inner_[side], outer = sidewalk_outer_[side];
  const double width = std::abs(outer - inner);
  const bool sidewalk = width >= 1.0;
  const double spacing = kind_ == StreetKind::kCity          ? 11.0
                         : kind_ == StreetKind::kResidential ? 22.0
                                                             : 45.0;
  // Towards the road from this side (the front of cabinets, lamp arms) and towards the camera
  // (sign faces: against the road's forward direction).
  const Eigen::Vector2f to_road = static_cast<float>(-sign) * scene_.road.RightXz();
  const float yaw_to_road = std::atan2(-to_road.y(), to_road.x());
  const double height = sidewalk ? curb_height_ : 0.0;
  for (double a = options_.min_along_m + rng.Uniform(0.0, spacing); a < options_.max_along_m;
       a += spacing * rng.Uniform(0.5, 1.5)) {
    ClutterKind kind;
    if (kind_ == StreetKind::kRoad || !sidewalk) {
      kind = rng.Bernoulli(0.6) ? ClutterKind::kSignPost : ClutterKind::kBollard;
    } else {
      kind = kAllClutterKinds[rng.Categorical({0.28, 0.14, 0.2, 0.2, 0.18})];
    }
    const double r = ClutterFootprintRadius(kind);
    // Lateral place: by the kerb (0.35-0.7 m in), cabinets and bins also at the back.
    double lateral = inner + sign * (r + rng.Uniform(0.25, 0.5));
    if ((kind == ClutterKind::kCabinet || kind == ClutterKind::kBin) && sidewalk &&
        rng.Bernoulli(0.5)) {
      lateral = outer - sign * (r + 0.1);
    }
    if (!sidewalk) lateral = inner + sign * rng.Uniform(0.5, 1.0);
    const int count =
        kind == ClutterKind::kBollard && rng.Bernoulli(0.4) ? rng.UniformInt(3, 6) : 1;
    for (int k = 0; k < count; ++k) {
      const double along = a + 1.6 * k;
      if (!Free(lateral, along, r) || InJunction(along, side, r + 0.5)) continue;
      Take(lateral, along, r);
      const Eigen::Vector3d base = At(lateral, along, height);
      // On a bend the road's heading turns with `along` (the same angles on a straight road).
      const float yaw_to_traffic = static_cast<float>(WrapYaw(Heading(along) + M_PI));
      const float yaw_to_road_here =
          scene_.road.curvature_per_m == 0.0f
              ? yaw_to_road
              : static_cast<float>(WrapYaw(Heading(along) + (side == 0 ? 0.5 : -0.5) * M_PI));
      const float yaw = kind == ClutterKind::kSignPost ? yaw_to_traffic : yaw_to_road_here;
      AddClutter(scene_, kind, base.cast<float>(), yaw, rng);
    }
  }
}

void StreetBuilder::Build() {
  kind_ = static_cast<StreetKind>(
      rng_.Categorical({options_.city_weight, options_.residential_weight, options_.road_weight}));
  // The camera sits in its lane with a small lateral offset; the road turns by a small angle.
  const double yaw = rng_.Normal(0.0, options_.road_yaw_sd_deg * M_PI / 180.0);
  ego_lateral_ = rng_.Normal(0.0, 0.25);
  scene_.ground_y_m = static_cast<float>(
      Round2(options_.camera_height_m + rng_.Normal(0.0, options_.camera_height_jitter_m)));
  scene_.road.forward_xz =
      Eigen::Vector2f(static_cast<float>(std::sin(yaw)), static_cast<float>(std::cos(yaw)));
  scene_.road.origin_xz = -static_cast<float>(ego_lateral_) * scene_.road.RightXz();
  curb_height_ = Round2(rng_.Uniform(0.1, 0.16));

  Materials();
  Lanes();
  RoadShape();
  Sidewalk(0);
  Sidewalk(1);
  Trams();
  for (int side = 0; side < 2; ++side) {
    const double width = parking_width_[side];
    const double centre = side == 0 ? carriage_left_ - 0.5 * width : carriage_right_ + 0.5 * width;
    Parking(centre, width, side);
  }
  Traffic();
  JunctionTraffic();
  Pedestrians();
  Roadside(0);
  Roadside(1);
  {
    // Street furniture from a generator of its own (one draw here), so that it does not shift
    // what the other builders draw.
    Rng furniture(rng_.Next());
    StreetFurniture(0, furniture);
    StreetFurniture(1, furniture);
  }

  // Light: sun elevation 15 to 65 degrees, any azimuth; overcast days get a weaker, bluer sun.
  Lighting& light = scene_.light;
  const double elevation = rng_.Uniform(15.0, 65.0) * M_PI / 180.0;
  const double azimuth = rng_.Uniform(0.0, 2.0 * M_PI);
  light.to_sun = Eigen::Vector3f(static_cast<float>(std::cos(elevation) * std::sin(azimuth)),
                                 static_cast<float>(-std::sin(elevation)),
                                 static_cast<float>(std::cos(elevation) * std::cos(azimuth)));
  light.cloudiness = static_cast<float>(rng_.Uniform(0.0, 1.0));
  const float sun =
      static_cast<float>(rng_.Uniform(1.6, 2.6)) * (light.cloudiness > 0.75f ? 0.35f : 1.0f);
  light.sun = sun * Rgb(1.0, 0.96, 0.9);
  const float ambient = static_cast<float>(rng_.Uniform(0.4, 0.65));
  light.sky_ambient = ambient * Rgb(0.9, 0.95, 1.05);
  light.sky_zenith = Vary(rng_, Rgb(0.45, 0.6, 0.9), 0.15);
  light.sky_horizon = Vary(rng_, Rgb(0.85, 0.88, 0.92), 0.08);
  light.haze_per_m = static_cast<float>(rng_.Uniform(1.0 / 900.0, 1.0 / 300.0));
  light.exposure = static_cast<float>(rng_.Uniform(0.85, 1.1) / (0.55 * sun + ambient));
  // The camera's white balance is not perfect: +-6% on red and blue, warmer under a low sun; its
  // noise varies with gain and temperature.
  const double warm = elevation < 25.0 * M_PI / 180.0 ? 0.04 : 0.0;
  const double wb_red = rng_.Uniform(0.94, 1.06) + warm;
  const double wb_blue = rng_.Uniform(0.94, 1.06) - warm;
  light.white_balance = Rgb(wb_red, 1.0, wb_blue);
  light.noise_scale = static_cast<float>(rng_.Uniform(0.8, 1.5));
  light.skyline_offset = static_cast<float>(rng_.Uniform(0.0, 1000.0));
  scene_.Finalize();
}

}  // namespace

void SceneOptions::Check() const {
  STEREODET_CHECK(city_weight >= 0 && residential_weight >= 0 && road_weight >= 0 &&
                  city_weight + residential_weight + road_weight > 0)
      << "street kind weights must be non-negative with a positive sum";
  STEREODET_CHECK(object_density >= 0.0 && object_density <= 10.0)
      << "object_density must be in [0, 10], got " << object_density;
  STEREODET_CHECK(min_along_m < max_along_m) << "min_along_m must be below max_along_m";
  STEREODET_CHECK(camera_height_m > 0.5 && camera_height_m < 5.0)
      << "camera_height_m must be in (0.5, 5), got " << camera_height_m;
  STEREODET_CHECK(camera_height_jitter_m >= 0.0 && road_yaw_sd_deg >= 0.0)
      << "jitters must be non-negative";
  const auto fraction = [](double f) { return f >= 0.0 && f <= 1.0; };
  STEREODET_CHECK(fraction(bend_fraction) && fraction(vertical_curve_fraction) &&
                  fraction(crown_fraction) && fraction(side_street_fraction))
      << "road shape fractions must be in [0, 1]";
  STEREODET_CHECK(min_bend_radius_m >= 50.0 && max_bend_radius_m >= min_bend_radius_m)
      << "bend radii must satisfy 50 <= min <= max, got " << min_bend_radius_m << ", "
      << max_bend_radius_m;
  STEREODET_CHECK(min_vertical_radius_m >= 100.0 && max_vertical_radius_m >= min_vertical_radius_m)
      << "vertical curve radii must satisfy 100 <= min <= max, got " << min_vertical_radius_m
      << ", " << max_vertical_radius_m;
  STEREODET_CHECK(max_grade_change >= 0.02 && max_grade_change <= 0.2)
      << "max_grade_change must be in [0.02, 0.2], got " << max_grade_change;
  STEREODET_CHECK(max_crossfall >= 0.01 && max_crossfall <= 0.1)
      << "max_crossfall must be in [0.01, 0.1], got " << max_crossfall;
  STEREODET_CHECK(pitch_sd_deg >= 0.0 && pitch_sd_deg <= 5.0 && roll_sd_deg >= 0.0 &&
                  roll_sd_deg <= 5.0)
      << "pitch_sd_deg and roll_sd_deg must be in [0, 5]";
}

Scene SampleScene(const SceneOptions& options, uint64_t seed) {
  options.Check();
  Scene scene;
  Rng rng(seed);
  Rng shape_rng(HashOf({seed, 0x726f6164u}));  // "road"
  StreetBuilder(scene, options, rng, shape_rng).Build();
  return scene;
}

}  // namespace stereodet
