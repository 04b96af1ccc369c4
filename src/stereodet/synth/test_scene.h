// Hand-made scenes for the synth tests: a flat ground and a few primitives at known poses.
#ifndef STEREODET_SYNTH_TEST_SCENE_H_
#define STEREODET_SYNTH_TEST_SCENE_H_

#include <string>

#include "stereodet/geometry/box.h"
#include "stereodet/synth/scene.h"

namespace stereodet::testing {

// A scene with a grey textured ground at y = 1.65 and no primitives (call Finalize() after adding).
inline Scene GroundOnlyScene() {
  Scene scene;
  scene.ground_y_m = 1.65f;
  Material ground;
  ground.pattern = Pattern::kAsphalt;
  ground.albedo = Eigen::Vector3f::Constant(0.2f);
  ground.lidar_reflectance = 0.2f;
  scene.road_material = scene.offroad_material = scene.AddMaterial(ground);
  Material plain;
  plain.pattern = Pattern::kPlain;
  plain.albedo = Eigen::Vector3f(0.6f, 0.3f, 0.2f);
  plain.contrast = 0.3f;
  plain.lidar_reflectance = 0.5f;
  scene.AddMaterial(plain);  // material 1
  return scene;
}

// Adds a labelled object made of one box exactly filling `box` (material 1).
inline int AddBoxObject(Scene& scene, const std::string& type, const Box3D& box) {
  SceneObject object;
  object.type = type;
  object.box = box;
  object.first_primitive = static_cast<int>(scene.primitives.size());
  object.num_primitives = 1;
  const int index = static_cast<int>(scene.objects.size());
  const Eigen::Vector3f centre = box.Centre().cast<float>();
  scene.primitives.push_back(
      MakeBox(centre,
              Eigen::Vector3f(static_cast<float>(box.l / 2), static_cast<float>(box.h / 2),
                              static_cast<float>(box.w / 2)),
              RotationY(static_cast<float>(box.rotation_y)), 1, index));
  scene.objects.push_back(object);
  return index;
}

inline Box3D MakeBox3D(double h, double w, double l, double x, double y, double z,
                       double rotation_y) {
  Box3D box;
  box.h = h, box.w = w, box.l = l;
  box.location = Eigen::Vector3d(x, y, z);
  box.rotation_y = rotation_y;
  return box;
}

}  // namespace stereodet::testing

#endif  // STEREODET_SYNTH_TEST_SCENE_H_
