// Test support (include from *_test.cc only): labels and detections with a 2D box and a fixed
// KITTI-like car-sized 3D box (1.5 x 1.6 x 3.9 m, 20 m ahead, x from the box's left edge), so that
// 2D cases can be written by hand and BEV / 3D fields are valid; plain 2D cars; and, for the
// devkit-overlap tests, objects from KITTI lines, footprints and the devkit's overlap of a pair.
#ifndef STEREODET_EVAL_TEST_OBJECTS_H_
#define STEREODET_EVAL_TEST_OBJECTS_H_

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "stereodet/eval/devkit_overlap_internal.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/object.h"

namespace stereodet::testing_objects {

inline Object Label(const std::string& type, Box2D box, double truncated = 0, int occluded = 0) {
  Object o;
  o.type = type;
  o.box = box;
  o.truncated = truncated;
  o.occluded = occluded;
  o.box3d.h = 1.5;
  o.box3d.w = 1.6;
  o.box3d.l = 3.9;
  o.box3d.location = Eigen::Vector3d(box.left / 100.0, 1.6, 20.0);
  return o;
}

// A detection: the label's fields, truncation and occlusion -1 (as detection files carry them).
inline Object Det(const std::string& type, Box2D box, double score) {
  Object o = Label(type, box);
  o.truncated = -1;
  o.occluded = -1;
  o.score = score;
  return o;
}

// A Car label (no score) or detection with a 2D box only (3D fields left at zero).
inline Object Car(Box2D box, std::optional<double> score = std::nullopt) {
  Object o;
  o.type = "Car";
  o.box = box;
  o.score = score;
  return o;
}

// A Car with a 2D box and an observation angle; a detection when score >= 0.
inline Object Car2D(double left, double top, double right, double bottom, double alpha,
                    double score = -1) {
  Object o;
  o.type = "Car";
  o.box = {left, top, right, bottom};
  o.alpha = alpha;
  if (score >= 0) o.score = score;  // labels carry no score
  return o;
}

// Options for Car, 2D, Moderate with `matcher`.
inline EvalOptions CarModerate2D(Matcher matcher) {
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  options.matcher = matcher;
  return options;
}

// The first object of a KITTI label or detection line.
inline Object Line(const std::string& text) {
  return ParseObjects(text, "test", {ObjectFileKind::kAny}).objects.at(0);
}

// A 3D box at (x, y, z) in rect, l x w x h metres, turned by rotation_y.
inline Box3D Footprint(double x, double z, double l, double w, double rotation_y, double y = 1.65,
                       double h = 1.5) {
  Box3D b;
  b.h = h;
  b.w = w;
  b.l = l;
  b.location = Eigen::Vector3d(x, y, z);
  b.rotation_y = rotation_y;
  return b;
}

// The devkit's overlap of a pair, which must be defined (a failure otherwise, and -1).
inline double Devkit(OverlapKind kind, const Box3D& det, const Box3D& label,
                     DevkitCriterion criterion = DevkitCriterion::kUnion) {
  const std::optional<double> o = DevkitBoxOverlap(kind, criterion, det, label);
  EXPECT_TRUE(o.has_value());
  return o.value_or(-1.0);
}

}  // namespace stereodet::testing_objects

#endif  // STEREODET_EVAL_TEST_OBJECTS_H_
