#include "stereodet/synth/road.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stereodet/synth/camera.h"
#include "stereodet/synth/random.h"
#include "stereodet/synth/scene.h"
#include "stereodet/synth/scene_sampler.h"
#include "stereodet/synth/test_scene.h"

namespace stereodet {
namespace {

// A profile with every term: pitch, roll, a sag 10-110 m ahead, a crown 2 m to the left.
GroundProfile FullProfile() {
  GroundProfile g;
  g.forward_xz = Eigen::Vector2d(std::sin(0.05), std::cos(0.05));
  g.pitch = 0.004;
  g.roll = -0.006;
  g.vertical_curvature_per_m = 1.0 / 1000.0;
  g.vertical_centre_m = 60.0;
  g.vertical_half_length_m = 50.0;
  g.crown_curvature_per_m = -0.025 / 3.5;
  g.crown_lateral_m = -2.0;
  g.crown_half_width_m = 3.5;
  return g;
}

// The hand-computed height: sag (k/2)((a-60)^2 - 60^2 + 120 a) inside, crown likewise.
TEST(GroundProfileTest, HeightMatchesHandComputedValues) {
  GroundProfile g = FullProfile();
  g.forward_xz = Eigen::Vector2d(0.0, 1.0);  // l = x, a = z
  EXPECT_EQ(g.Height(0.0, 0.0), 0.0);
  // a = 30 on the curve (s = -30): q = 900; q(-60) = 2*50*60 - 2500 = 3500 (beyond the curve),
  // q'(-60) = -100: 0.0005 (900 - 3500 + 100 * 30) + 0.004 * 30 = 0.2 + 0.12.
  EXPECT_NEAR(g.Height(0.0, 30.0), 0.32, 1e-12);
  // a = 200, beyond the curve (s = 140 > 50): q = 2*50*140 - 2500 = 11500:
  // 0.0005 (11500 - 3500 + 100*200) + 0.8 = 14 + 0.8.
  EXPECT_NEAR(g.Height(0.0, 200.0), 14.8, 1e-9);
  // l = -2 (the crown, s = 0): q(2) = 4, q'(2) = 4: k_c/2 (0 - 4 - 4 * (-2)) - 0.006 * (-2).
  const double kc = -0.025 / 3.5;
  EXPECT_NEAR(g.Height(-2.0, 0.0), 0.5 * kc * 4.0 + 0.012, 1e-12);
  // Slopes at the origin are the pitch and roll.
  const Eigen::Vector2d grad = g.Gradient(0.0, 0.0);
  EXPECT_NEAR(grad.x(), -0.006, 1e-12);
  EXPECT_NEAR(grad.y(), 0.004, 1e-12);
}

TEST(GroundProfileTest, GradientAndNormalMatchFiniteDifferencesAndAreContinuous) {
  const GroundProfile g = FullProfile();
  Rng rng(7);
  for (int i = 0; i < 500; ++i) {
    const double x = rng.Uniform(-30, 30), z = rng.Uniform(-40, 200);
    const double h = 1e-4;
    const Eigen::Vector2d fd((g.Height(x + h, z) - g.Height(x - h, z)) / (2 * h),
                             (g.Height(x, z + h) - g.Height(x, z - h)) / (2 * h));
    EXPECT_NEAR((g.Gradient(x, z) - fd).norm(), 0.0, 1e-7) << x << " " << z;
    // The normal is perpendicular to both tangents of the surface y = -Height.
    const Eigen::Vector3d n = g.Normal(x, z).cast<double>();
    EXPECT_NEAR(n.norm(), 1.0, 1e-6);
    EXPECT_LT(n.y(), -0.99);
    EXPECT_NEAR(n.dot(Eigen::Vector3d(1.0, -fd.x(), 0.0)), 0.0, 1e-6);
    EXPECT_NEAR(n.dot(Eigen::Vector3d(0.0, -fd.y(), 1.0)), 0.0, 1e-6);
    Eigen::Vector3f n2;
    EXPECT_NEAR(g.HeightAndNormal(x, z, &n2), g.Height(x, z), 1e-12);
    EXPECT_NEAR((n2 - g.Normal(x, z)).norm(), 0.0f, 1e-7f);
  }
  // C1 at the curve's ends (a = 10 and 110 along the profile's heading).
  for (const double a : {10.0, 110.0}) {
    const Eigen::Vector2d p = a * g.forward_xz;
    const Eigen::Vector2d before = g.Gradient(p.x() - 1e-9 * g.forward_xz.x(), p.y() - 1e-9);
    const Eigen::Vector2d after = g.Gradient(p.x() + 1e-9 * g.forward_xz.x(), p.y() + 1e-9);
    EXPECT_NEAR((before - after).norm(), 0.0, 1e-8);
  }
}

// Rays from a camera-like height: the hit lies on the surface, and sampling the ray finely finds
// no earlier crossing (the hit is the first); a miss never goes below the ground.
TEST(GroundProfileTest, RayHitsLieOnTheSurfaceAndAreTheFirstCrossing) {
  const GroundProfile g = FullProfile();
  const float base = 1.65f;
  Rng rng(11);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3f origin(static_cast<float>(rng.Uniform(-5, 5)),
                                 static_cast<float>(rng.Uniform(-0.2, 1.6)),
                                 static_cast<float>(rng.Uniform(-5, 5)));
    const Eigen::Vector3f dir(static_cast<float>(rng.Uniform(-1, 1)),
                              static_cast<float>(rng.Uniform(-0.05, 0.4)),
                              static_cast<float>(rng.Uniform(-1, 1)));
    const Ray ray(origin, dir);
    const float t = g.Intersect(ray, base, 1e-3f, 400.0f);
    const auto above = [&](double s) {  // F > 0: above the ground
      const Eigen::Vector3d p = (origin + static_cast<float>(s) * dir).cast<double>();
      return base - g.Height(p.x(), p.z()) - p.y();
    };
    const double t_end = t == kNoHit ? 400.0 : t;
    for (int k = 1; k < 400; ++k) {
      const double s = t_end * k / 400.0;
      ASSERT_GT(above(s), -1e-4) << "an earlier crossing at t = " << s << " (ray " << i << ")";
    }
    if (t == kNoHit) continue;
    ++hits;
    const Eigen::Vector3f p = ray.At(t);
    EXPECT_NEAR(p.y(), base - g.Height(p.x(), p.z()), 2e-4 * (1.0 + t / 50.0)) << i;
  }
  EXPECT_GT(hits, 1000);
}

TEST(GroundProfileTest, FlatProfileIsThePlane) {
  const GroundProfile g;
  ASSERT_TRUE(g.Flat());
  Rng rng(3);
  for (int i = 0; i < 200; ++i) {
    const Ray ray(Eigen::Vector3f(0.0f, 0.0f, 0.0f),
                  Eigen::Vector3f(static_cast<float>(rng.Uniform(-1, 1)),
                                  static_cast<float>(rng.Uniform(0.01, 0.5)), 1.0f));
    EXPECT_EQ(g.Intersect(ray, 1.65f, 1e-3f, kNoHit), 1.65f / ray.direction.y());
  }
  EXPECT_EQ(g.Height(12.0, 40.0), 0.0);
  EXPECT_EQ(g.Normal(3.0, 4.0), Eigen::Vector3f(0.0f, -1.0f, 0.0f));
  // Upward rays miss.
  EXPECT_EQ(g.Intersect(Ray({0, 0, 0}, {0, -0.1f, 1}), 1.65f, 1e-3f, kNoHit), kNoHit);
}

TEST(RoadArcTest, RoundTripsAndTurnsByTheCurvature) {
  const Eigen::Vector2f origin(0.3f, 0.0f), forward(std::sin(0.04f), std::cos(0.04f));
  for (const float k : {0.0f, 1.0f / 250.0f, -1.0f / 400.0f, 1.0f / 2500.0f}) {
    Road road;
    road.origin_xz = origin;
    road.forward_xz = forward;
    road.curvature_per_m = k;
    for (const float lateral : {-20.0f, -3.3f, 0.0f, 1.5f, 25.0f}) {
      for (const float along : {-40.0f, 0.0f, 12.5f, 90.0f, 180.0f}) {
        const Eigen::Vector2f xz = road.FromRoad(lateral, along);
        const Eigen::Vector2f back = road.ToRoad(xz.x(), xz.y());
        EXPECT_NEAR(back.x(), lateral, 2e-4) << k;
        EXPECT_NEAR(back.y(), along, 2e-4) << k;
      }
    }
    // The centre line's tangent is the heading at `along` (rotation_y: atan2(-hz, hx)).
    for (const float along : {0.0f, 50.0f, 150.0f}) {
      const Eigen::Vector2f d =
          road.FromRoad(0.0f, along + 0.05f) - road.FromRoad(0.0f, along - 0.05f);
      EXPECT_NEAR(std::atan2(-d.y(), d.x()), road.ForwardYawAt(along), 2e-3) << k << " " << along;
      EXPECT_NEAR(d.norm(), 0.1f, 1e-4);  // arc length
    }
    // Lateral offsets are perpendicular distances from the centre line.
    const Eigen::Vector2f p0 = road.FromRoad(0.0f, 60.0f), p1 = road.FromRoad(4.0f, 60.0f);
    EXPECT_NEAR((p1 - p0).norm(), 4.0f, 1e-4);
  }
  // Positive curvature bends to the right (+x for a road heading +z).
  Road right;
  right.curvature_per_m = 1.0f / 300.0f;
  EXPECT_GT(right.FromRoad(0.0f, 80.0f).x(), 10.0f);
}

// Sampled scenes: the scene's ground hits (camera and LiDAR path) lie on the profile, objects
// stand on the ground (a kerb at most above it), and the straight, flat option gives the plane.
TEST(RoadSceneTest, SampledScenesStandOnTheirGround) {
  SceneOptions options;
  int shaped = 0;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    const Scene scene = SampleScene(options, seed);
    if (scene.road.curvature_per_m != 0.0f || scene.ground.vertical_curvature_per_m != 0.0)
      ++shaped;
    for (const SceneObject& o : scene.objects) {
      const Eigen::Vector3d& x = o.box.location;
      const double above =
          scene.GroundY(static_cast<float>(x.x()), static_cast<float>(x.z())) - x.y();
      EXPECT_GE(above, -0.006) << o.type << " below the ground, seed " << seed;
      EXPECT_LE(above, 0.2) << o.type << " floating, seed " << seed;
    }
    Rng rng(seed);
    for (int i = 0; i < 200; ++i) {
      const Ray ray(Eigen::Vector3f(0.0f, 0.0f, 0.0f),
                    Eigen::Vector3f(static_cast<float>(rng.Uniform(-0.6, 0.6)),
                                    static_cast<float>(rng.Uniform(0.02, 0.3)), 1.0f));
      const SurfaceHit hit = scene.Trace(ray);
      if (hit.kind != SurfaceHit::Kind::kGround) continue;
      EXPECT_NEAR(hit.point.y(), scene.GroundY(hit.point.x(), hit.point.z()), 1e-6);
      EXPECT_NEAR((ray.At(hit.t) - hit.point).norm(), 0.0, 2e-4 * (1.0 + hit.t / 50.0));
      EXPECT_LT(hit.normal.y(), -0.99);
    }
  }
  EXPECT_GE(shaped, 4);

  options.road_shapes = false;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    const Scene scene = SampleScene(options, seed);
    EXPECT_TRUE(scene.ground.Flat());
    EXPECT_EQ(scene.road.curvature_per_m, 0.0f);
    EXPECT_TRUE(scene.road.side_streets.empty());
    for (const SceneObject& o : scene.objects) {
      EXPECT_LE(scene.ground_y_m - o.box.location.y(), 0.2);
    }
  }
}

// Traffic ahead in the ego lane keeps its rear at least 6 m ahead of the camera (version 5):
// no vehicle's footprint covers a point of the 1.6 m wide corridor from the camera to 5.5 m ahead
// (the ego car's bumper is about 2 m ahead of the camera). Version 4 put the vehicle's centre 6 m
// ahead, so a truck's rear could reach the camera. The corridor is tested point by point in each
// box's own frame: u along its length (cos ry, -sin ry), v across it.
TEST(RoadSceneTest, TrafficAheadKeepsClearOfTheEgoCar) {
  SceneOptions options;
  int vehicles_near = 0;
  for (uint64_t seed = 1; seed <= 400; ++seed) {
    const Scene scene = SampleScene(options, seed);
    for (const SceneObject& o : scene.objects) {
      if (o.type == "Pedestrian" || o.type == "Cyclist" || o.type == "Person_sitting") continue;
      const Box3D& b = o.box;
      const double c = std::cos(b.rotation_y), s = std::sin(b.rotation_y);
      if (std::abs(b.location.x()) < 2.0 && b.location.z() > 0.0 && b.location.z() < 15.0)
        ++vehicles_near;
      for (double x = -0.8; x <= 0.8; x += 0.4) {
        for (double z = 0.0; z <= 5.5; z += 0.25) {
          const double dx = x - b.location.x(), dz = z - b.location.z();
          const double u = dx * c - dz * s, v = dx * s + dz * c;
          EXPECT_FALSE(std::abs(u) <= 0.5 * b.l && std::abs(v) <= 0.5 * b.w)
              << o.type << " (l " << b.l << " m, centre z " << b.location.z()
              << " m) covers the ego corridor at x " << x << ", z " << z << ", seed " << seed;
        }
      }
    }
  }
  // The property is not empty: vehicles do stand just ahead in the ego lane.
  EXPECT_GE(vehicles_near, 20);
}

// The planes file's plane: the ground's own plane when that is one (flat, or tilted by pitch and
// roll alone), and close to the ground's tangent under the camera on a curved one.
TEST(RoadSceneTest, TrueGroundPlaneIsTheLeastSquaresPlaneOfTheGround) {
  const Calibration calib = SynthCalibration(1242, 375);
  Scene scene = testing::GroundOnlyScene();
  scene.ground_y_m = 1.7f;
  EXPECT_EQ(TrueGroundPlane(scene, calib, 1242, 375), Eigen::Vector4d(0.0, -1.0, 0.0, 1.7f));
  // A tilted plane: pitch 0.02 (rising ahead), roll -0.01.
  scene.ground.pitch = 0.02;
  scene.ground.roll = -0.01;
  const Eigen::Vector4d plane = TrueGroundPlane(scene, calib, 1242, 375);
  const Eigen::Vector3d expected = -Eigen::Vector3d(-0.01, 1.0, 0.02).normalized();
  EXPECT_NEAR((plane.head<3>() - expected).norm(), 0.0, 1e-6);
  EXPECT_NEAR(plane[3], -expected.y() * 1.7f, 1e-5);
  // On a sag the plane lies between the tangents over the fit's 3-20 m.
  scene.ground.vertical_curvature_per_m = 1.0 / 500.0;
  scene.ground.vertical_centre_m = 0.0;
  scene.ground.vertical_half_length_m = 100.0;
  const Eigen::Vector4d sag = TrueGroundPlane(scene, calib, 1242, 375);
  const double slope = sag.z() / sag.y();  // dHeight/dz of the plane
  EXPECT_GT(slope, 0.02 + 3.0 / 500.0);
  EXPECT_LT(slope, 0.02 + 20.0 / 500.0);
}

}  // namespace
}  // namespace stereodet
