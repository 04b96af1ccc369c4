// Random street scenes in the style of KITTI's: a road with lanes and markings (straight or
// bending, with grade changes, crossfall and side streets: road.h), kerbs and sidewalks, buildings,
// walls, fences, hedges, trees and poles, parked rows and traffic of cars, vans and trucks,
// pedestrians, people sitting, cyclists, rarely trams and other vehicles (Misc).
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
  // Road shape (synth/road.h; since settings version 4). false: straight, flat roads without side
  // streets (the plane y = camera height, as before version 4); the options below are then unused.
  bool road_shapes = true;
  // Share of frames whose road bends, with a radius log-uniform in [min, max] (left or right).
  double bend_fraction = 0.5;
  double min_bend_radius_m = 250.0;
  double max_bend_radius_m = 2500.0;
  // Share of frames with a vertical curve (crest or sag, equally often) centred 0-80 m ahead: a
  // grade change uniform in [0.02, max_grade_change] over a curve of radius log-uniform in [min,
  // max] metres, straight grades before and after it.
  double vertical_curve_fraction = 0.5;
  double max_grade_change = 0.06;
  double min_vertical_radius_m = 800.0;
  double max_vertical_radius_m = 5000.0;
  // Share of crowned roads: a parabolic cross-section falling from the centre line (between the
  // two directions) with a crossfall uniform in [0.01, max_crossfall] at the carriageway's edges.
  double crown_fraction = 0.7;
  double max_crossfall = 0.03;
  // The car's pitch and roll on its springs relative to the road under it (standard deviations).
  double pitch_sd_deg = 0.3;
  double roll_sd_deg = 0.3;
  // Share of frames with a side street (left, right or both) 12-70 m ahead, 6-10 m wide.
  double side_street_fraction = 0.35;

  void Check() const;  // throws std::invalid_argument
};

// Samples one scene from `seed` (the caller derives it from the data set seed and frame index) and
// finalises it (builds the BVH). Object boxes and poses are rounded to KITTI's 0.01 precision
// before the geometry is built from them, so the labels written with two decimals are exact.
Scene SampleScene(const SceneOptions& options, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_SCENE_SAMPLER_H_
