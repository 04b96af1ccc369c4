#include "stereodet/synth/shapes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

#include "stereodet/synth/bvh.h"
#include "stereodet/synth/random.h"

namespace stereodet {
namespace {

TEST(ShapesTest, AxisAlignedBoxHitByRayAlongZ) {
  const Primitive box =
      MakeBox(Eigen::Vector3f(0, 0, 10), Eigen::Vector3f(1, 1, 2), Eigen::Matrix3f::Identity(), 0);
  const Ray ray(Eigen::Vector3f(0.5f, 0.2f, 0), Eigen::Vector3f(0, 0, 1));
  EXPECT_FLOAT_EQ(box.Intersect(ray, 0.0f, kNoHit), 8.0f);
  EXPECT_EQ(box.Intersect(ray, 0.0f, 7.0f), kNoHit);  // beyond t_max
  EXPECT_TRUE(box.Normal(ray.At(8.0f)).isApprox(Eigen::Vector3f(0, 0, -1)));
  // A ray that passes beside.
  EXPECT_EQ(box.Intersect(Ray(Eigen::Vector3f(1.5f, 0, 0), Eigen::Vector3f(0, 0, 1)), 0.0f, kNoHit),
            kNoHit);
}

TEST(ShapesTest, RotatedBoxUsesKittiYaw) {
  // rotation_y = pi/2 turns the local x axis (length 4) onto -z: the box is 4 m deep along z.
  const Primitive box = MakeBox(Eigen::Vector3f(0, 0, 10), Eigen::Vector3f(2, 1, 0.5f),
                                RotationY(static_cast<float>(M_PI / 2)), 0);
  const Ray ray(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 0, 1));
  EXPECT_NEAR(box.Intersect(ray, 0.0f, kNoHit), 8.0f, 1e-5);
  EXPECT_TRUE(RotationY(0.3f).col(0).isApprox(Eigen::Vector3f(std::cos(0.3f), 0, -std::sin(0.3f))));
}

TEST(ShapesTest, CylinderSideAndCap) {
  // Vertical pole of radius 0.5 from y = -2 to y = 2 at z = 10.
  const Primitive pole =
      MakeCylinder(Eigen::Vector3f(0, 0, 10), 0.5f, 2.0f, Eigen::Matrix3f::Identity(), 0);
  EXPECT_NEAR(pole.Intersect(Ray(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit),
              9.5f, 1e-5);
  // From above, straight down onto the cap at y = -2 (y is down).
  EXPECT_NEAR(
      pole.Intersect(Ray(Eigen::Vector3f(0.2f, -5, 10), Eigen::Vector3f(0, 1, 0)), 0, kNoHit), 3.0f,
      1e-5);
  EXPECT_TRUE(pole.Normal(Eigen::Vector3f(0.2f, -2, 10)).isApprox(Eigen::Vector3f(0, -1, 0)));
  // Above the top: missed.
  EXPECT_EQ(pole.Intersect(Ray(Eigen::Vector3f(0, -3, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit),
            kNoHit);
}

TEST(ShapesTest, EllipsoidHit) {
  const Primitive e = MakeEllipsoid(Eigen::Vector3f(0, 0, 10), Eigen::Vector3f(1, 2, 3),
                                    Eigen::Matrix3f::Identity(), 0);
  EXPECT_NEAR(e.Intersect(Ray(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit), 7.0f,
              1e-5);
  EXPECT_NEAR(e.Intersect(Ray(Eigen::Vector3f(0, -5, 10), Eigen::Vector3f(0, 1, 0)), 0, kNoHit),
              3.0f, 1e-5);
}

// A unit-half cube rounded by a sphere of radius 1.2 about its centre: hand-computable hits.
TEST(ShapesTest, RoundedBoxHitsTheBoxOrTheSphereWhicheverIsInside) {
  const Primitive p = MakeRoundedBox(Eigen::Vector3f(0, 0, 10), Eigen::Vector3f(1, 1, 1),
                                     Eigen::Matrix3f::Identity(), Eigen::Vector3f::Zero(),
                                     Eigen::Vector3f::Constant(1.2f), 0);
  // Through the face's centre the sphere lies outside the face: the flat face at z = 9.
  EXPECT_NEAR(p.Intersect(Ray(Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit), 9.0f,
              1e-5);
  const Eigen::Vector3f n0 = p.Normal(Eigen::Vector3f(0.1f, 0.1f, 9.0f));
  EXPECT_NEAR(n0.z(), -1.0f, 1e-6);
  // At (0.6, 0.6) the sphere cuts the corner: z = 10 - sqrt(1.44 - 0.72), normal along the radius.
  const float t =
      p.Intersect(Ray(Eigen::Vector3f(0.6f, 0.6f, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit);
  const float z = 10.0f - std::sqrt(0.72f);
  EXPECT_NEAR(t, z, 1e-5);
  const Eigen::Vector3f n = p.Normal(Eigen::Vector3f(0.6f, 0.6f, z));
  EXPECT_NEAR(n.x(), 0.6f / 1.2f, 1e-5);
  EXPECT_NEAR(n.y(), 0.6f / 1.2f, 1e-5);
  EXPECT_NEAR(n.z(), -std::sqrt(0.72f) / 1.2f, 1e-5);
  // At (0.9, 0.9) the sphere (0.81 + 0.81 > 1.44) leaves nothing: a miss, though the box is hit.
  EXPECT_EQ(p.Intersect(Ray(Eigen::Vector3f(0.9f, 0.9f, 0), Eigen::Vector3f(0, 0, 1)), 0, kNoHit),
            kNoHit);
  EXPECT_FALSE(p.Contains(Eigen::Vector3f(0.9f, 0.9f, 10.0f)));
  EXPECT_TRUE(p.Contains(Eigen::Vector3f(0.9f, 0.0f, 10.0f)));
  // From inside: the exit point.
  EXPECT_NEAR(p.Intersect(Ray(Eigen::Vector3f(0, 0, 10), Eigen::Vector3f(1, 0, 0)), 0, kNoHit),
              1.0f, 1e-5);
  // Bounds are the box's.
  EXPECT_NEAR(p.Bounds().min.z(), 9.0f, 1e-6);
  EXPECT_NEAR(p.Bounds().max.x(), 1.0f, 1e-6);
}

TEST(ShapesTest, RoundedBoxRejectsAnEllipsoidAwayFromItsCentre) {
  EXPECT_THROW(
      MakeRoundedBox(Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones(), Eigen::Matrix3f::Identity(),
                     Eigen::Vector3f(2, 0, 0), Eigen::Vector3f::Ones(), 0),
      std::invalid_argument);
  EXPECT_THROW(
      MakeRoundedBox(Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones(), Eigen::Matrix3f::Identity(),
                     Eigen::Vector3f::Zero(), Eigen::Vector3f(1, 0, 1), 0),
      std::invalid_argument);
}

// Property: the first hit of a random rounded box equals the first point of the ray that a fine
// march finds inside it (brute force on Contains), and the normal points out of it.
TEST(ShapesTest, RoundedBoxHitMatchesAMarchAlongTheRay) {
  Rng rng(11);
  int hits = 0;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector3f h(rng.Uniform(0.3, 2), rng.Uniform(0.3, 2), rng.Uniform(0.3, 2));
    const Eigen::Vector3f rc(rng.Uniform(-0.3, 0.3) * h.x(), rng.Uniform(-0.3, 0.3) * h.y(),
                             rng.Uniform(-0.3, 0.3) * h.z());
    const Eigen::Vector3f rr = h.cwiseProduct(
        Eigen::Vector3f(rng.Uniform(0.9, 2), rng.Uniform(0.9, 2), rng.Uniform(0.9, 2)));
    const Eigen::Matrix3f r =
        Eigen::AngleAxisf(static_cast<float>(rng.Uniform(0, 6.3)), Eigen::Vector3f::UnitY())
            .toRotationMatrix();
    const Primitive p = MakeRoundedBox(Eigen::Vector3f(0, 0, 0), h, r, rc, rr, 0);
    for (int k = 0; k < 25; ++k) {
      const Eigen::Vector3f origin(rng.Uniform(-6, 6), rng.Uniform(-6, 6), rng.Uniform(-6, 6));
      const Eigen::Vector3f target(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
      const Ray ray(origin, (target - origin).normalized());
      if (p.Contains(origin, 0.0f)) continue;
      const float t = p.Intersect(ray, 0.0f, kNoHit);
      constexpr float kStep = 1e-3f;
      float march = kNoHit;
      for (float s = 0.0f; s < 20.0f; s += kStep) {
        if (p.Contains(ray.At(s), 0.0f)) {
          march = s;
          break;
        }
      }
      if (march == kNoHit) {
        EXPECT_EQ(t, kNoHit);
        continue;
      }
      ++hits;
      ASSERT_NE(t, kNoHit);
      EXPECT_NEAR(t, march, 2 * kStep);
      const Eigen::Vector3f n = p.Normal(ray.At(t));
      EXPECT_NEAR(n.norm(), 1.0f, 1e-4);
      EXPECT_FALSE(p.Contains(ray.At(t) + 0.01f * n, 0.0f));
    }
  }
  EXPECT_GT(hits, 200);
}

// Random primitives of all kinds and orientations.
std::vector<Primitive> RandomPrimitives(Rng& rng, int n) {
  std::vector<Primitive> prims;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f c(rng.Uniform(-20, 20), rng.Uniform(-3, 3), rng.Uniform(2, 60));
    const Eigen::Vector3f h(rng.Uniform(0.1, 3), rng.Uniform(0.1, 3), rng.Uniform(0.1, 3));
    const Eigen::Matrix3f r =
        (Eigen::AngleAxisf(static_cast<float>(rng.Uniform(0, 6.3)), Eigen::Vector3f::UnitY()) *
         Eigen::AngleAxisf(static_cast<float>(rng.Uniform(0, 6.3)), Eigen::Vector3f::UnitX()))
            .toRotationMatrix();
    switch (i % 3) {
      case 0:
        prims.push_back(MakeBox(c, h, r, 0, i));
        break;
      case 1:
        prims.push_back(MakeCylinder(c, h.x(), h.y(), r, 0, i));
        break;
      default:
        prims.push_back(MakeEllipsoid(c, h, r, 0, i));
        break;
    }
  }
  return prims;
}

TEST(ShapesTest, BoundsContainSurfacePoints) {
  Rng rng(3);
  const std::vector<Primitive> prims = RandomPrimitives(rng, 60);
  for (const Primitive& p : prims) {
    const Aabb b = p.Bounds();
    for (int k = 0; k < 200; ++k) {
      const Ray ray(p.centre + Eigen::Vector3f(rng.Uniform(-30, 30), rng.Uniform(-30, 30),
                                               rng.Uniform(-30, 30)),
                    Eigen::Vector3f(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1)));
      const float t = p.Intersect(ray, 0.0f, kNoHit);
      if (t == kNoHit) continue;
      const Eigen::Vector3f x = ray.At(t);
      EXPECT_TRUE(p.Contains(x, 1e-3f));
      EXPECT_TRUE((x.array() >= b.min.array() - 1e-3f).all() &&
                  (x.array() <= b.max.array() + 1e-3f).all());
    }
  }
}

TEST(BvhTest, ClosestHitMatchesBruteForce) {
  Rng rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const std::vector<Primitive> prims = RandomPrimitives(rng, 1 + trial * 40);
    const Bvh bvh(prims);
    for (int k = 0; k < 500; ++k) {
      const Ray ray(Eigen::Vector3f(rng.Uniform(-2, 2), rng.Uniform(-2, 2), 0),
                    Eigen::Vector3f(rng.Uniform(-0.8, 0.8), rng.Uniform(-0.3, 0.3), 1));
      float best = kNoHit;
      int best_index = -1;
      for (int i = 0; i < static_cast<int>(prims.size()); ++i) {
        const float t = prims[i].Intersect(ray, 1e-3f, best);
        if (t < best) best = t, best_index = i;
      }
      const RayHit hit = bvh.Intersect(ray, 1e-3f, kNoHit);
      EXPECT_EQ(hit.primitive, best_index);
      if (best_index >= 0) {
        EXPECT_FLOAT_EQ(hit.t, best);
      }
      const RayHit any = bvh.AnyHit(ray, 1e-3f, kNoHit);
      EXPECT_EQ(any.primitive >= 0, best_index >= 0);
    }
  }
}

TEST(BvhTest, EmptyBvhMissesEverything) {
  const std::vector<Primitive> none;
  const Bvh bvh(none);
  EXPECT_EQ(
      bvh.Intersect(Ray(Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ()), 0, kNoHit).primitive,
      -1);
  EXPECT_EQ(bvh.AnyHit(Ray(Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ()), 0, kNoHit).primitive,
            -1);
}

TEST(RngTest, DeterministicAndInRange) {
  Rng a(5), b(5);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a.Next(), b.Next());
  Rng c(6);
  double sum = 0, sum2 = 0;
  for (int i = 0; i < 20000; ++i) {
    const double u = c.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    const double n = c.Normal(0, 1);
    sum += n, sum2 += n * n;
    const int k = c.UniformInt(-2, 3);
    ASSERT_GE(k, -2);
    ASSERT_LE(k, 3);
  }
  EXPECT_NEAR(sum / 20000, 0.0, 0.05);
  EXPECT_NEAR(sum2 / 20000, 1.0, 0.05);
}

}  // namespace
}  // namespace stereodet
