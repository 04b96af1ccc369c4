// The labelled objects of the synthetic scenes, built from primitives (shapes.h): cars, vans,
// trucks, trams, trailers (Misc), pedestrians, people sitting and cyclists (docs/synth.md has the
// parts of each).
//
// An object is built in its own frame (x forward along its length, y down, z across its width),
// centred in x and z and standing on the ground, then placed with the bottom centre at the label
// box's `location`, turned by its `rotation_y` (KITTI's convention, shapes.h's RotationY). Its
// label box is the tight extent of its parts, so a label and the pixels and LiDAR points of its
// object agree exactly.
#ifndef STEREODET_SYNTH_OBJECTS_H_
#define STEREODET_SYNTH_OBJECTS_H_

#include <cstdint>
#include <string>

#include "stereodet/geometry/box.h"
#include "stereodet/synth/random.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

// Appends a labelled object of `type` to `scene` and returns its index in scene.objects:
//   - its parts, appended to scene.primitives (SceneObject::first_primitive, num_primitives) with
//     Primitive::object set to that index, and the materials they use, appended to
//     scene.materials;
//   - its SceneObject, whose box is the parts' extent rounded to 0.01 m at box.location and
//     box.rotation_y (taken as given: the caller rounds them to the label precision it wants).
// The vehicles (Car, Van, Truck, Tram, Misc) are built to fill box.l, box.w and box.h exactly, so
// their label box is `box` for sizes in KITTI's ranges (SampleDims in scene_sampler.cc). The people
// (Pedestrian, Person_sitting, Cyclist) take only box.h, their body height; their length and width
// follow from the pose (stride, pedals), and their label height is box.h to within a few
// centimetres. Random details (wheel size, cabin shape, colours, stride) come from `rng`.
// Requires: `type` is one of the eight classes above (throws std::invalid_argument otherwise, after
// adding materials), positive sizes.
// `x` rounded to the two decimals that KITTI label files carry, so that a scene's boxes, poses
// and yaws equal their labels read back (metres or radians alike).
double Round2(double x);

int AddObject(Scene& scene, const std::string& type, const Box3D& box, Rng& rng);

// AddObject with a generator seeded by `seed`.
int AddSimpleObject(Scene& scene, const std::string& type, const Box3D& box, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_OBJECTS_H_
