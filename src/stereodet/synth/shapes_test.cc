#include "stereodet/synth/shapes.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

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
