// Random street scenes in the style of KITTI's: a straight road with lanes and markings, kerbs and
// sidewalks, buildings, walls, fences, hedges, trees and poles, parked rows and traffic of cars,
// vans and trucks, pedestrians, people sitting, cyclists, rarely trams and other vehicles (Misc).
//
// Three kinds of street are drawn: "city" (continuous facades, parking on both sides, many
// pedestrians), "residential" (houses behind front yards with fences and hedges, trees, parked
// cars) and "road" (few buildings, vegetation, guard rails, moving traffic). Object counts are
// tuned so that, after labelling, a frame has about KITTI's 5.4 labelled objects and 1.5 DontCare
// regions (docs/synth.md compares the statistics). The objects themselves are built by objects.h,
// their colours and materials come from materials.h.
#ifndef STEREODET_SYNTH_SCENE_SAMPLER_H_
#define STEREODET_SYNTH_SCENE_SAMPLER_H_

#include <cstdint>

#include "stereodet/synth/scene.h"

namespace stereodet {

struct SceneOptions {
  // Relative frequencies of the three street kinds.
  double city_weight = 0.4;
  double residential_weight = 0.4;
  double road_weight = 0.2;
  // Multiplies the number of vehicles, pedestrians and cyclists (1 = tuned to KITTI).
  double object_density = 1.0;
  // Objects are placed from this far behind the camera (for the LiDAR's full circle) ...
  double min_along_m = -30.0;
  // ... to this far ahead.
  double max_along_m = 85.0;
  double camera_height_m = 1.65;         // above the road (KITTI: 1.65 m)
  double camera_height_jitter_m = 0.03;  // per-frame standard deviation
  double road_yaw_sd_deg = 3.0;          // heading of the road relative to the camera

  void Check() const;  // throws std::invalid_argument
};

// Samples one scene from `seed` (the caller derives it from the data set seed and frame index) and
// finalises it (builds the BVH). Object boxes and poses are rounded to KITTI's 0.01 precision
// before the geometry is built from them, so the labels written with two decimals are exact.
Scene SampleScene(const SceneOptions& options, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_SCENE_SAMPLER_H_
