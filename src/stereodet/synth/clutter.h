// Street furniture of the synthetic scenes: the unlabelled clutter that stands on sidewalks and
// occludes the labelled objects behind it (lamp and sign posts, litter bins, bollards, utility
// cabinets).
//
// Every item is built from primitives (shapes.h) standing on a surface point `base` (rect frame,
// the bottom centre of the item) and turned by `yaw_rad` about the rect y axis (KITTI's
// rotation_y convention: the item's local x axis, its front, becomes (cos yaw, 0, -sin yaw)).
// Its primitives are background (Primitive::object = -1), so the labels module counts them as
// occluders of whatever labelled object lies behind them: a label's visible fraction is the share
// of its silhouette where the left camera's object-id buffer holds that object (labels.h).
#ifndef STEREODET_SYNTH_CLUTTER_H_
#define STEREODET_SYNTH_CLUTTER_H_

#include <Eigen/Core>
#include <array>

#include "stereodet/synth/random.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

enum class ClutterKind {
  kSignPost,  // a galvanised post 2.6-3.2 m high with one or two signs (square, round or a plate)
  kLampPost,  // a street lamp 5-8 m high with an arm and a lamp head over the street
  kBin,       // a litter bin: a cylinder 0.8-1.0 m high on a post, or a square bin
  kBollard,   // a bollard 0.8-1.1 m high with a reflective band and a rounded cap
  kCabinet,   // a utility cabinet 1.0-1.5 m high, 0.5-1.4 m wide, with a lid and posters/graffiti
};

inline constexpr std::array<ClutterKind, 5> kAllClutterKinds = {
    ClutterKind::kSignPost, ClutterKind::kLampPost, ClutterKind::kBin, ClutterKind::kBollard,
    ClutterKind::kCabinet};

// The greatest distance (m) of any part of an item of `kind` from its base's vertical axis, for
// keeping items apart; the lamp post's arm and lamp head are not counted (they reach over the
// street at 5 m and more).
double ClutterFootprintRadius(ClutterKind kind);

// The greatest height (m) of an item of `kind` above its base.
double ClutterMaxHeight(ClutterKind kind);

// What AddClutter appended.
struct ClutterPlacement {
  int first_primitive = 0;
  int num_primitives = 0;
  double height_m = 0.0;  // the item's top above its base
};

// Appends an item of `kind` at `base_rect` (the bottom centre, rect frame, y down), turned by
// `yaw_rad`, to scene.primitives (object -1) with its materials (scene.materials). Sizes,
// colours and details come from `rng`. Call Scene::Finalize() after the last primitive.
ClutterPlacement AddClutter(Scene& scene, ClutterKind kind, const Eigen::Vector3f& base_rect,
                            float yaw_rad, Rng& rng);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_CLUTTER_H_
