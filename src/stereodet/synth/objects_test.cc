#include "stereodet/synth/objects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/synth/test_scene.h"

namespace stereodet {
namespace {

using testing::GroundOnlyScene;
using testing::MakeBox3D;

// Float parts: positions are good to well under 0.1 mm (shapes.h).
constexpr double kFloatTol = 1e-4;
// The label box is the parts' extent rounded to 0.01 m, so it may be 5 mm smaller or larger.
constexpr double kRoundTol = 0.005 + kFloatTol;

// The world-frame bounding box of an object's parts.
Aabb WorldBounds(const Scene& scene, const SceneObject& object) {
  Aabb bounds;
  for (int i = 0; i < object.num_primitives; ++i) {
    bounds.Extend(scene.primitives[object.first_primitive + i].Bounds());
  }
  return bounds;
}

// The bounding box of an object's parts in its label box's frame: origin at the box's bottom
// centre (`location`), x along the length, y down, z across (Box3D's axes).
Aabb BoxFrameBounds(const Scene& scene, const SceneObject& object) {
  const Eigen::Matrix3f box_from_world =
      RotationY(static_cast<float>(object.box.rotation_y)).transpose();
  const Eigen::Vector3f location = object.box.location.cast<float>();
  Aabb bounds;
  for (int i = 0; i < object.num_primitives; ++i) {
    Primitive p = scene.primitives[object.first_primitive + i];
    p.centre = box_from_world * (p.centre - location);
    p.world_from_local = box_from_world * p.world_from_local;
    bounds.Extend(p.Bounds());
  }
  return bounds;
}

TEST(ObjectsTest, CarAtKnownPoseFillsItsBox) {
  Scene scene = GroundOnlyScene();
  const int materials_before = static_cast<int>(scene.materials.size());
  const Box3D box = MakeBox3D(/*h=*/1.5, /*w=*/1.6, /*l=*/4.0, 2.0, 1.65, 15.0, /*rotation_y=*/0.0);
  const int index = AddSimpleObject(scene, "Car", box, 1);
  ASSERT_EQ(index, 0);
  ASSERT_EQ(scene.objects.size(), 1u);
  const SceneObject& car = scene.objects[0];
  EXPECT_EQ(car.type, "Car");
  // A car's parts span exactly l x w x h, and the sizes given have two decimals: the label is
  // `box`.
  EXPECT_EQ(car.box, box);
  // Body, glass cabin, roof and four wheels, with paint, glass, tyre and a dark trim material.
  EXPECT_EQ(car.first_primitive, 0);
  EXPECT_EQ(car.num_primitives, 7);
  EXPECT_EQ(scene.primitives.size(), 7u);
  EXPECT_EQ(static_cast<int>(scene.materials.size()), materials_before + 4);
  for (const Primitive& p : scene.primitives) {
    EXPECT_EQ(p.object, 0);
    EXPECT_GE(p.material, materials_before);
  }
  // With rotation_y = 0 the length runs along x: x in 2 -+ 2, y from the roof at 1.65 - 1.5 down to
  // the ground at 1.65, z in 15 -+ 0.8.
  const Aabb world = WorldBounds(scene, car);
  EXPECT_NEAR(world.min.x(), 0.0, kFloatTol);
  EXPECT_NEAR(world.max.x(), 4.0, kFloatTol);
  EXPECT_NEAR(world.min.y(), 0.15, kFloatTol);
  EXPECT_NEAR(world.max.y(), 1.65, kFloatTol);
  EXPECT_NEAR(world.min.z(), 14.2, kFloatTol);
  EXPECT_NEAR(world.max.z(), 15.8, kFloatTol);
}

TEST(ObjectsTest, QuarterTurnPutsTheLengthAlongZ) {
  // rotation_y = pi/2 turns the car's length onto the camera's z axis (shapes.h: local x becomes
  // (cos, 0, -sin) = (0, 0, -1)): 1.6 m wide in x, 4 m deep in z.
  Scene scene = GroundOnlyScene();
  const Box3D box = MakeBox3D(1.5, 1.6, 4.0, 2.0, 1.65, 15.0, M_PI / 2);
  const SceneObject& car = scene.objects[AddSimpleObject(scene, "Car", box, 1)];
  EXPECT_EQ(car.box, box);
  const Aabb world = WorldBounds(scene, car);
  EXPECT_NEAR(world.min.x(), 1.2, kFloatTol);
  EXPECT_NEAR(world.max.x(), 2.8, kFloatTol);
  EXPECT_NEAR(world.min.y(), 0.15, kFloatTol);
  EXPECT_NEAR(world.max.y(), 1.65, kFloatTol);
  EXPECT_NEAR(world.min.z(), 13.0, kFloatTol);
  EXPECT_NEAR(world.max.z(), 17.0, kFloatTol);
}

TEST(ObjectsTest, TruckHasThreeAxlesAboveSevenAndAHalfMetres) {
  // Cab, windscreen, cargo box and chassis, plus two wheels per axle; the cargo box has its own
  // material.
  for (const double length : {7.0, 9.0}) {
    Scene scene = GroundOnlyScene();
    const int materials_before = static_cast<int>(scene.materials.size());
    const Box3D box = MakeBox3D(3.2, 2.5, length, -4.0, 1.65, 30.0, 0.3);
    const SceneObject& truck = scene.objects[AddSimpleObject(scene, "Truck", box, 2)];
    EXPECT_EQ(truck.box, box) << length;
    EXPECT_EQ(truck.num_primitives, 4 + (length > 7.5 ? 6 : 4)) << length;
    EXPECT_EQ(static_cast<int>(scene.materials.size()), materials_before + 5) << length;
  }
}

TEST(ObjectsTest, CyclistLengthIsItsWheelbasePlusOneWheel) {
  // A rider of 1.72 m (scale 1): wheels of radius 0.34 m centred 0.53 m before and behind the
  // centre, so l = 2 * 0.53 + 2 * 0.34 = 1.74; the head's top is at h and the wheels touch the
  // ground.
  Scene scene = GroundOnlyScene();
  const Box3D box = MakeBox3D(1.72, 0.0, 0.0, 1.0, 1.65, 12.0, 0.0);
  const SceneObject& cyclist = scene.objects[AddSimpleObject(scene, "Cyclist", box, 3)];
  EXPECT_DOUBLE_EQ(cyclist.box.l, 1.74);
  EXPECT_DOUBLE_EQ(cyclist.box.h, 1.72);
  EXPECT_EQ(cyclist.box.location, box.location);
  EXPECT_EQ(cyclist.box.rotation_y, 0.0);
}

TEST(ObjectsTest, PeopleTakeTheirHeightFromTheBox) {
  // The head's top is at box.h; the feet end at most a few centimetres above the lowest part.
  for (const char* type : {"Pedestrian", "Person_sitting"}) {
    for (uint64_t seed = 1; seed <= 10; ++seed) {
      Scene scene = GroundOnlyScene();
      const double h = std::string(type) == "Pedestrian" ? 1.75 : 1.27;
      const SceneObject& person = scene.objects[AddSimpleObject(
          scene, type, MakeBox3D(h, 0.0, 0.0, -1.0, 1.65, 8.0, 0.5), seed)];
      EXPECT_LE(person.box.h, h + kRoundTol) << type << " seed " << seed;
      EXPECT_GE(person.box.h, h - 0.03 - kRoundTol) << type << " seed " << seed;
      EXPECT_GT(person.box.l, 0.0);
      EXPECT_GT(person.box.w, 0.0);
    }
  }
}

// Every class, at random poses: the label box holds every part and is tight on all six faces, the
// parts rest on the ground at `location`, and the object owns exactly the primitives it added.
TEST(ObjectsTest, LabelBoxIsTheTightExtentOfTheParts) {
  struct Case {
    const char* type;
    double h, w, l;
  };
  const std::vector<Case> cases = {
      {"Car", 1.45, 1.7, 4.2},       {"Van", 2.2, 1.95, 5.3}, {"Truck", 3.4, 2.5, 10.0},
      {"Tram", 3.4, 2.6, 22.0},      {"Misc", 1.6, 1.8, 3.2}, {"Pedestrian", 1.8, 0, 0},
      {"Person_sitting", 1.3, 0, 0}, {"Cyclist", 1.65, 0, 0},
  };
  Rng pose_rng(42);
  for (const Case& c : cases) {
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      SCOPED_TRACE(std::string(c.type) + " seed " + std::to_string(seed));
      Scene scene = GroundOnlyScene();
      // Something already in the scene: the new object's primitives and index come after it.
      testing::AddBoxObject(scene, "Car", MakeBox3D(1.5, 1.6, 4.0, 5.0, 1.65, 20.0, 0.0));
      const int primitives_before = static_cast<int>(scene.primitives.size());
      const Box3D box = MakeBox3D(c.h, c.w, c.l, pose_rng.Uniform(-10, 10), 1.65,
                                  pose_rng.Uniform(5, 60), pose_rng.Uniform(-M_PI, M_PI));
      const int index = AddSimpleObject(scene, c.type, box, seed);
      ASSERT_EQ(index, 1);
      const SceneObject& object = scene.objects[index];
      EXPECT_EQ(object.type, c.type);
      EXPECT_EQ(object.first_primitive, primitives_before);
      EXPECT_EQ(object.first_primitive + object.num_primitives,
                static_cast<int>(scene.primitives.size()));
      for (int i = object.first_primitive; i < object.first_primitive + object.num_primitives;
           ++i) {
        EXPECT_EQ(scene.primitives[i].object, index);
        EXPECT_LT(scene.primitives[i].material, static_cast<int>(scene.materials.size()));
      }
      EXPECT_EQ(object.box.location, box.location);
      EXPECT_EQ(object.box.rotation_y, box.rotation_y);
      if (c.l > 0) {  // the vehicles fill the box they were given
        EXPECT_DOUBLE_EQ(object.box.l, c.l);
        EXPECT_DOUBLE_EQ(object.box.w, c.w);
        EXPECT_DOUBLE_EQ(object.box.h, c.h);
      }
      // In the box frame the parts span [-l/2, l/2] x [-h, 0] x [-w/2, w/2] (y down, 0 the ground).
      const Aabb local = BoxFrameBounds(scene, object);
      const double l = object.box.l, w = object.box.w, h = object.box.h;
      EXPECT_NEAR(local.min.x(), -l / 2, kRoundTol);
      EXPECT_NEAR(local.max.x(), l / 2, kRoundTol);
      EXPECT_NEAR(local.min.y(), -h, kRoundTol);
      EXPECT_NEAR(local.max.y(), 0.0, kFloatTol);
      EXPECT_NEAR(local.min.z(), -w / 2, kRoundTol);
      EXPECT_NEAR(local.max.z(), w / 2, kRoundTol);
      // The same seed builds the same object.
      Scene again = GroundOnlyScene();
      testing::AddBoxObject(again, "Car", MakeBox3D(1.5, 1.6, 4.0, 5.0, 1.65, 20.0, 0.0));
      const SceneObject& copy = again.objects[AddSimpleObject(again, c.type, box, seed)];
      EXPECT_EQ(copy.box, object.box);
      ASSERT_EQ(copy.num_primitives, object.num_primitives);
      for (int i = 0; i < object.num_primitives; ++i) {
        EXPECT_EQ(again.primitives[copy.first_primitive + i].centre,
                  scene.primitives[object.first_primitive + i].centre);
      }
    }
  }
}

// The curved hull reaches its label box: rays cast at each of the six faces of a car's box
// (along its axes, on a grid over the face) first hit the car on the face itself, and no part
// pokes out (no hit before it).
TEST(ObjectsTest, CurvedCarReachesEveryFaceOfItsBox) {
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Scene scene = GroundOnlyScene();
    const double h = seed % 2 ? 1.45 : 1.7;  // low cars and tall ones (SUVs, estates)
    const Box3D box = MakeBox3D(h, 1.75, 4.3, 0.0, 1.65, 20.0, 0.0);
    const SceneObject& car = scene.objects[AddSimpleObject(scene, "Car", box, seed)];
    const Eigen::Vector3f centre(0.0f, 1.65f - 0.5f * static_cast<float>(h), 20.0f);
    const Eigen::Vector3f half(2.15f, 0.5f * static_cast<float>(h), 0.875f);
    const auto first_hit = [&](const Ray& ray) {
      float best = kNoHit;
      for (int i = 0; i < car.num_primitives; ++i) {
        best = std::min(best, scene.primitives[car.first_primitive + i].Intersect(ray, 0, best));
      }
      return best;
    };
    for (int axis = 0; axis < 3; ++axis) {
      for (float side : {-1.0f, 1.0f}) {
        float nearest = kNoHit;
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        for (int i = 0; i <= 40; ++i) {
          for (int j = 0; j <= 40; ++j) {
            Eigen::Vector3f origin = centre;
            origin[axis] += side * (half[axis] + 5.0f);
            origin[a] += half[a] * (i / 20.0f - 1.0f);
            origin[b] += half[b] * (j / 20.0f - 1.0f);
            Eigen::Vector3f dir = Eigen::Vector3f::Zero();
            dir[axis] = -side;
            nearest = std::min(nearest, first_hit(Ray(origin, dir)));
          }
        }
        // The box is rounded to 0.01 m (5 mm), the grid's step is under 11 cm.
        EXPECT_GE(nearest, 5.0f - 0.006f) << "axis " << axis << " side " << side;
        EXPECT_LE(nearest, 5.0f + 0.02f) << "axis " << axis << " side " << side;
      }
    }
  }
}

TEST(ObjectsTest, UnknownTypeThrows) {
  Scene scene = GroundOnlyScene();
  EXPECT_THROW(AddSimpleObject(scene, "Bus", MakeBox3D(3, 2.5, 12, 0, 1.65, 20, 0), 1),
               std::invalid_argument);
  EXPECT_TRUE(scene.objects.empty());
  EXPECT_TRUE(scene.primitives.empty());
}

}  // namespace
}  // namespace stereodet

namespace stereodet {
namespace {

// A pedestrian stands on its shoes (the parts that reach the ground are two boxes of one
// material), and its hair stays inside the head's height, so the label is as tall as the box
// asks, for walking and standing poses, with and without bags.
TEST(ObjectsTest, PedestrianStandsOnShoesAndHairKeepsItsHeight) {
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    Scene scene = testing::GroundOnlyScene();
    const double h = 1.62;
    const SceneObject& person = scene.objects[AddSimpleObject(
        scene, "Pedestrian", testing::MakeBox3D(h, 0.0, 0.0, 1.0, 1.65, 9.0, 0.0), seed)];
    // Two legs, two shoes, two arms, torso, head, hair; a bag or a backpack adds one.
    EXPECT_GE(person.num_primitives, 9) << seed;
    EXPECT_LE(person.num_primitives, 10) << seed;
    EXPECT_NEAR(person.box.h, h, kRoundTol) << seed;
    std::vector<int> on_ground;
    for (int i = person.first_primitive; i < person.first_primitive + person.num_primitives; ++i) {
      if (scene.primitives[i].Bounds().max.y() > 1.65f - 1e-3f) on_ground.push_back(i);
    }
    ASSERT_EQ(on_ground.size(), 2u) << seed;
    EXPECT_EQ(scene.primitives[on_ground[0]].kind, ShapeKind::kBox);
    EXPECT_EQ(scene.primitives[on_ground[0]].material, scene.primitives[on_ground[1]].material);
  }
}

}  // namespace
}  // namespace stereodet
