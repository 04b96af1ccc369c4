#include "stereodet/synth/clutter.h"

#include <gtest/gtest.h>

#include <cmath>

#include "stereodet/synth/camera.h"
#include "stereodet/synth/labels.h"
#include "stereodet/synth/test_scene.h"

namespace stereodet {
namespace {

using testing::AddBoxObject;
using testing::GroundOnlyScene;
using testing::MakeBox3D;

constexpr float kTol = 1e-4f;

class ClutterKindTest : public ::testing::TestWithParam<ClutterKind> {};

// Every item stands on its base (its lowest point at the base's height), stays within its
// footprint radius of the base's vertical axis (the lamp post's arm and head excepted) and below
// its maximum height, is background (object -1) and uses materials that exist.
TEST_P(ClutterKindTest, StandsOnItsBaseWithinItsBounds) {
  const ClutterKind kind = GetParam();
  for (uint64_t seed = 1; seed <= 30; ++seed) {
    Scene scene = GroundOnlyScene();
    Rng rng(seed);
    const Eigen::Vector3f base(3.0f, 1.53f, 12.0f);  // on a 12 cm kerb
    const float yaw = static_cast<float>(0.2 * seed);
    const ClutterPlacement placed = AddClutter(scene, kind, base, yaw, rng);
    ASSERT_EQ(placed.first_primitive, 0);
    ASSERT_EQ(placed.num_primitives, static_cast<int>(scene.primitives.size()));
    ASSERT_GE(placed.num_primitives, 1);
    float lowest = -1e9f;  // the largest y: y points down
    for (int i = 0; i < placed.num_primitives; ++i) {
      const Primitive& p = scene.primitives[i];
      EXPECT_EQ(p.object, -1);
      ASSERT_GE(p.material, 0);
      ASSERT_LT(p.material, static_cast<int>(scene.materials.size()));
      const Aabb b = p.Bounds();
      lowest = std::max(lowest, b.max.y());
      EXPECT_GE(b.min.y(), base.y() - ClutterMaxHeight(kind) - kTol) << "seed " << seed;
      EXPECT_LE(b.max.y(), base.y() + kTol);
      // Horizontal distance of the part's points from the base axis: the bounds' corners in x/z
      // overestimate it for turned parts, so test points of the surface: ray casts towards the
      // axis from the outside at the part's mid-height (and the bounds' centre).
      const bool lamp_arm = kind == ClutterKind::kLampPost && b.min.y() < base.y() - 4.0f;
      if (lamp_arm) continue;
      const Eigen::Vector3f c = b.Centre();
      for (int k = 0; k < 16; ++k) {
        const float a = static_cast<float>(k * M_PI / 8.0);
        const Eigen::Vector3f dir(std::cos(a), 0.0f, std::sin(a));
        const Eigen::Vector3f origin(base.x() + 5.0f * dir.x(), c.y(), base.z() + 5.0f * dir.z());
        const float t = p.Intersect(Ray(origin, -dir), 0.0f, 10.0f);
        if (t == kNoHit) continue;
        const Eigen::Vector3f hit = origin - t * dir;
        const float r = std::hypot(hit.x() - base.x(), hit.z() - base.z());
        EXPECT_LE(r, ClutterFootprintRadius(kind) + kTol) << "seed " << seed << " part " << i;
      }
    }
    EXPECT_NEAR(lowest, base.y(), kTol) << "seed " << seed;
    EXPECT_NEAR(
        placed.height_m,
        base.y() -
            [&] {
              float top = 1e9f;
              for (const Primitive& p : scene.primitives) top = std::min(top, p.Bounds().min.y());
              return top;
            }(),
        kTol);
  }
}

// A ray straight down the axis from above hits the item's top with an upward normal; one towards
// the axis at knee height hits it (every kind reaches down to the ground there) with a normal
// facing back along the ray.
TEST_P(ClutterKindTest, RaysHitItsSurface) {
  const ClutterKind kind = GetParam();
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    Scene scene = GroundOnlyScene();
    Rng rng(seed);
    const Eigen::Vector3f base(0.0f, 1.65f, 10.0f);
    const ClutterPlacement placed = AddClutter(scene, kind, base, 0.0f, rng);
    scene.Finalize();
    const Ray down(Eigen::Vector3f(base.x(), base.y() - 20.0f, base.z()), Eigen::Vector3f::UnitY());
    const SurfaceHit top = scene.Trace(down);
    ASSERT_EQ(top.kind, SurfaceHit::Kind::kPrimitive) << "seed " << seed;
    EXPECT_EQ(top.object, -1);
    EXPECT_NEAR(top.normal.norm(), 1.0f, 1e-4f);
    EXPECT_LT(top.normal.dot(down.direction), 0.0f);
    if (kind != ClutterKind::kLampPost) {
      // Straight down the axis the first thing is the top (the lamp's head hangs off-axis).
      EXPECT_NEAR(base.y() - top.point.y(), placed.height_m, 0.01f) << "seed " << seed;
    }
    for (int k = 0; k < 8; ++k) {
      const float a = static_cast<float>(k * M_PI / 4.0);
      const Eigen::Vector3f dir(std::cos(a), 0.0f, std::sin(a));
      const Ray in(base + Eigen::Vector3f(0.0f, -0.05f, 0.0f) - 3.0f * dir, dir);
      const SurfaceHit side = scene.Trace(in);
      ASSERT_EQ(side.kind, SurfaceHit::Kind::kPrimitive) << "seed " << seed << " k " << k;
      EXPECT_NEAR(side.normal.norm(), 1.0f, 1e-4f);
      EXPECT_LT(side.normal.dot(dir), 0.0f);
      EXPECT_LE(std::hypot(side.point.x() - base.x(), side.point.z() - base.z()),
                ClutterFootprintRadius(kind) + kTol);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllKinds, ClutterKindTest, ::testing::ValuesIn(kAllClutterKinds));

TEST(ClutterTest, SameSeedSameItem) {
  for (ClutterKind kind : kAllClutterKinds) {
    Scene a = GroundOnlyScene(), b = GroundOnlyScene();
    Rng ra(7), rb(7);
    AddClutter(a, kind, Eigen::Vector3f(1, 1.65f, 8), 0.5f, ra);
    AddClutter(b, kind, Eigen::Vector3f(1, 1.65f, 8), 0.5f, rb);
    ASSERT_EQ(a.primitives.size(), b.primitives.size());
    for (size_t i = 0; i < a.primitives.size(); ++i) {
      EXPECT_EQ(a.primitives[i].centre, b.primitives[i].centre);
      EXPECT_EQ(a.primitives[i].half_extent, b.primitives[i].half_extent);
    }
  }
}

// Two cabinets standing between the camera and a car seen from behind hide the lower part of
// its rear (at least 0.5 m of its 1.7 m width each, from 1 m up to the ground): the car's label
// says so (occluded > 0), while the same car alone is fully visible. The labels module counts
// background primitives as occluders.
TEST(ClutterTest, CabinetsInFrontOccludeACar) {
  constexpr int kWidth = 621, kHeight = 188;
  const Calibration calib = SynthCalibration(kWidth, kHeight);
  const Box3D car = MakeBox3D(1.5, 1.7, 4.2, 0.0, 1.65, 14.0, 0.5 * M_PI);
  const auto label_of = [&](bool with_cabinet) {
    Scene scene = GroundOnlyScene();
    AddBoxObject(scene, "Car", car);
    if (with_cabinet) {
      Rng rng(3);
      for (float x : {-0.45f, 0.45f}) {  // fronts towards the camera
        AddClutter(scene, ClutterKind::kCabinet, Eigen::Vector3f(x, 1.65f, 10.5f),
                   static_cast<float>(0.5 * M_PI), rng);
      }
    }
    scene.Finalize();
    RenderRequest request;
    request.width = kWidth;
    request.height = kHeight;
    request.object_ids = true;
    RenderOptions options;
    options.shadows = false;
    const cv::Mat ids = RenderCamera(scene, calib, request, options).object_id;
    const LabelSet set = MakeLabels(scene, calib, ids);
    EXPECT_EQ(set.labels.size(), 1u);
    return set.labels.empty() ? Object{} : set.labels[0];
  };
  const Object alone = label_of(false), hidden = label_of(true);
  EXPECT_EQ(alone.occluded, 0);
  EXPECT_GE(hidden.occluded, 1);
  // The 2D box is amodal: the cabinet does not shrink it.
  EXPECT_NEAR(hidden.box.left, alone.box.left, 1e-9);
  EXPECT_NEAR(hidden.box.right, alone.box.right, 1e-9);
}

}  // namespace
}  // namespace stereodet
