#include "stereodet/synth/materials.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "stereodet/synth/texture.h"

namespace stereodet {
namespace {

TEST(MaterialsTest, LumaWeighsTheChannelsAsRec709) {
  EXPECT_FLOAT_EQ(Luma(Rgb(1, 0, 0)), 0.2126f);
  EXPECT_FLOAT_EQ(Luma(Rgb(0, 1, 0)), 0.7152f);
  EXPECT_FLOAT_EQ(Luma(Rgb(0, 0, 1)), 0.0722f);
  EXPECT_FLOAT_EQ(Luma(Rgb(1, 1, 1)), 1.0f);
}

TEST(MaterialsTest, MakeMaterialDerivesTheLidarReflectanceFromBrightness) {
  // White: 0.08 + 0.5 * 1; a mid grey of luma 0.4: 0.08 + 0.2.
  const Material white = MakeMaterial(Pattern::kPaving, Rgb(1, 1, 1), 0.25f);
  EXPECT_EQ(white.pattern, Pattern::kPaving);
  EXPECT_EQ(white.albedo, Rgb(1, 1, 1));
  EXPECT_FLOAT_EQ(white.contrast, 0.25f);
  EXPECT_FLOAT_EQ(white.lidar_reflectance, 0.58f);
  EXPECT_FLOAT_EQ(MakeMaterial(Pattern::kPlain, Rgb(0.4, 0.4, 0.4), 0.1f).lidar_reflectance, 0.28f);
  // An explicit reflectance (glass, tyres) is kept, and the other fields keep their defaults.
  const Material glass = MakeMaterial(Pattern::kGlass, Rgb(1, 1, 1), 0.15f, 0.05f);
  EXPECT_FLOAT_EQ(glass.lidar_reflectance, 0.05f);
  const Material defaults;
  EXPECT_EQ(glass.albedo2, defaults.albedo2);
  EXPECT_EQ(glass.scale_m, defaults.scale_m);
  EXPECT_EQ(glass.specular, defaults.specular);
}

TEST(MaterialsTest, VaryScalesBrightnessWithinTheAmountAndClipsAtOne) {
  Rng rng(7);
  const Eigen::Vector3f c = Rgb(0.2, 0.4, 0.8);
  float lowest = 2.0f, highest = 0.0f;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3f v = Vary(rng, c, 0.3);
    // One factor for all channels: the hue is kept (until the blue channel clips at 1).
    const float factor = v.x() / c.x();
    EXPECT_GE(factor, 0.7f - 1e-6f);
    EXPECT_LT(factor, 1.3f + 1e-6f);
    EXPECT_NEAR(v.y(), factor * c.y(), 1e-6f);
    EXPECT_NEAR(v.z(), std::min(1.0f, factor * c.z()), 1e-6f);
    lowest = std::min(lowest, factor);
    highest = std::max(highest, factor);
  }
  // The draws cover the range (2000 uniform draws: the gaps at the ends are ~0.0003 on average).
  EXPECT_LT(lowest, 0.71f);
  EXPECT_GT(highest, 1.29f);
  EXPECT_EQ(Vary(rng, c, 0.0), c);
}

TEST(MaterialsTest, PaletteColoursAreValidAndVaried) {
  Rng rng(11);
  Eigen::Vector3f car_sum = Eigen::Vector3f::Zero();
  int dark_cars = 0;
  for (int i = 0; i < 1000; ++i) {
    for (const Eigen::Vector3f& c : {CarColour(rng), ClothColour(rng)}) {
      EXPECT_TRUE((c.array() >= 0.0f).all() && (c.array() <= 1.0f).all()) << c.transpose();
    }
    const Eigen::Vector3f car = CarColour(rng);
    car_sum += car;
    dark_cars += Luma(car) < 0.05f ? 1 : 0;
  }
  // Black is 18 % of the mix (luma 0.025 x [0.7, 1.3]); white and silver keep the mean well above
  // it.
  EXPECT_GT(dark_cars, 120);
  EXPECT_LT(dark_cars, 250);
  EXPECT_GT(Luma(car_sum / 1000.0f), 0.15f);
}

}  // namespace
}  // namespace stereodet

namespace stereodet {
namespace {

TEST(MaterialsTest, ClothMaterialDrawsEveryVariantAndDenimOnlyBelow) {
  Rng rng(5);
  std::array<int, 4> upper{}, lower{};
  for (int i = 0; i < 2000; ++i) {
    const Material u = ClothMaterial(rng, false), l = ClothMaterial(rng, true);
    ASSERT_EQ(u.pattern, Pattern::kCloth);
    ASSERT_LT(u.variant, 4);
    ASSERT_LT(l.variant, 4);
    ++upper[u.variant];
    ++lower[l.variant];
    if (u.variant == 1 || u.variant == 2) {
      EXPECT_GE(u.scale_m, 0.03f);
      EXPECT_LE(u.scale_m, 0.12f);
    }
    EXPECT_GE(u.contrast, 0.2f);
    EXPECT_LE(u.contrast, 0.35f);
  }
  EXPECT_EQ(upper[3], 0);  // no denim jackets
  for (int v = 0; v < 3; ++v) EXPECT_GT(upper[v], 100) << v;
  for (int v = 0; v < 4; ++v) EXPECT_GT(lower[v], 100) << v;
  // Shares as documented: plain 75 % (45 % below, where denim takes 30 %), stripes 15 %,
  // checks 10 %.
  EXPECT_NEAR(upper[0] / 2000.0, 0.75, 0.04);
  EXPECT_NEAR(lower[3] / 2000.0, 0.3, 0.04);
  EXPECT_NEAR(upper[1] / 2000.0, 0.15, 0.03);
  EXPECT_NEAR(upper[2] / 2000.0, 0.1, 0.03);
}

// A scene of one box of `material` (centre, half extents; rect frame, axis-aligned) and no ground
// in view: a wall to sample a texture on with rays from the origin.
Scene OneBoxScene(const Material& material, const Eigen::Vector3f& centre,
                  const Eigen::Vector3f& half) {
  Scene scene;
  const int m = scene.AddMaterial(material);
  scene.primitives.push_back(MakeBox(centre, half, Eigen::Matrix3f::Identity(), m));
  scene.ground_y_m = 100.0f;
  scene.Finalize();
  return scene;
}

// A striped garment (period 0.1 m, stripes 4.5 cm wide centred on multiples of the period) shows
// albedo2 on a stripe's centre line and albedo between stripes, on a box face 10 m ahead.
TEST(MaterialsTest, StripedClothHasStripesOfItsSecondColour) {
  Material cloth = MakeMaterial(Pattern::kCloth, Rgb(0.1, 0.1, 0.1), 0.0f);
  cloth.variant = 1;
  cloth.albedo2 = Rgb(0.6, 0.5, 0.4);
  cloth.scale_m = 0.1f;
  // A box 1 m high from y = 1.0 (bottom) up to y = 0.0, its face towards the camera at z = 10.
  const Scene scene =
      OneBoxScene(cloth, Eigen::Vector3f(0.0f, 0.5f, 10.5f), Eigen::Vector3f(1.0f, 0.5f, 0.5f));
  const auto albedo_at = [&](float height) {
    const Ray ray(Eigen::Vector3f::Zero(), Eigen::Vector3f(0.02f, (1.0f - height) / 10.0f, 1.0f));
    const SurfaceHit hit = scene.Trace(ray);
    EXPECT_EQ(hit.kind, SurfaceHit::Kind::kPrimitive);
    return SurfaceAlbedo(scene, hit, 1e-3f);
  };
  EXPECT_TRUE(albedo_at(0.3f).isApprox(cloth.albedo2, 1e-3f)) << albedo_at(0.3f).transpose();
  EXPECT_TRUE(albedo_at(0.35f).isApprox(cloth.albedo, 1e-3f)) << albedo_at(0.35f).transpose();
  EXPECT_TRUE(albedo_at(0.7f).isApprox(cloth.albedo2, 1e-3f));
}

// Paving (version 6) is laid in a random bond: within a course the joints come a stone apart
// (give or take their 6 % wander on each side), but the courses' joints do not line up, as a
// regular grid's would (which block matching cannot tell apart along an image row). The joints are
// made to stand out with a bright joint colour (a test value) on a wall 10 m ahead.
TEST(MaterialsTest, PavingCoursesHaveJointsAStoneApartThatDoNotLineUp) {
  Material paving = MakeMaterial(Pattern::kPaving, Rgb(0.1, 0.1, 0.1), 0.0f);
  paving.albedo2 = Rgb(10.0, 10.0, 10.0);
  paving.scale_m = 0.3f;
  const Scene scene =
      OneBoxScene(paving, Eigen::Vector3f(0.0f, 0.0f, 10.5f), Eigen::Vector3f(3.0f, 1.5f, 0.5f));
  const float s = paving.scale_m;
  std::vector<float> phases;
  for (int line = 0; line < 9; ++line) {
    const float y = -1.2f + 0.3f * line + 0.07f;
    std::vector<float> joints;  // centres of the bright runs along x
    int bright = 0, samples = 0;
    float run_start = 0.0f;
    bool in_run = false;
    for (float x = -2.5f; x <= 2.5f; x += 0.002f, ++samples) {
      const SurfaceHit hit =
          scene.Trace(Ray(Eigen::Vector3f::Zero(), Eigen::Vector3f(x, y, 10.0f)));
      ASSERT_EQ(hit.kind, SurfaceHit::Kind::kPrimitive);
      const bool is_joint = SurfaceAlbedo(scene, hit, 1e-3f).x() > 1.0f;
      bright += is_joint;
      if (is_joint && !in_run) run_start = x;
      if (!is_joint && in_run) joints.push_back(0.5f * (run_start + x));
      in_run = is_joint;
    }
    if (bright > samples / 2) continue;  // the scan ran along a joint between courses
    ASSERT_GE(joints.size(), 12u) << "line " << line;
    for (size_t i = 1; i < joints.size(); ++i) {
      EXPECT_GT(joints[i] - joints[i - 1], 0.85f * s) << "line " << line << " joint " << i;
      EXPECT_LT(joints[i] - joints[i - 1], 1.15f * s) << "line " << line << " joint " << i;
    }
    phases.push_back(std::fmod(joints[0] + 10.0f * s, s));
  }
  ASSERT_GE(phases.size(), 6u);
  // The largest circular difference of two courses' phases: near 0 for a regular grid.
  float largest = 0.0f;
  for (float a : phases) {
    for (float b : phases) {
      const float d = std::abs(a - b);
      largest = std::max(largest, std::min(d, s - d));
    }
  }
  EXPECT_GT(largest, 0.25f * s);
}

}  // namespace
}  // namespace stereodet
