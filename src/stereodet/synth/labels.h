// KITTI labels for a rendered synthetic frame.
//
// Semantics follow KITTI's object benchmark (devkit readme):
//  - box (2D): the amodal extent of the object in the left image, i.e. the bounding box of the
//    projection of its actual shape (all its parts, occluded ones included), clipped to the image
//    [0, W-1] x [0, H-1]. KITTI's annotators drew boxes around the whole object in the image, not
//    around its visible pixels (an occluded car still has a car-sized box), and the projection of
//    the shape is tighter than the projected 3D box's 8 corners, as their boxes are.
//  - truncated: the fraction of the object's silhouette outside the image, [0, 1].
//  - occluded: from the fraction of the in-image silhouette that is visible in the rendered
//    object-id buffer: >= 0.8 -> 0 (fully visible), >= 0.4 -> 1 (partly), >= 0.1 -> 2 (largely),
//    below -> 3 (unknown: too little is visible to tell).
//  - alpha = rotation_y - atan2(x, z) of the location; h, w, l, location (bottom centre, rect
//    frame) and rotation_y come from the scene object.
//  - DontCare: objects that are visible but too far (beyond max_depth_m) or too small (box height
//    below min_height_px) to label, as KITTI marks regions its annotators skipped.
// Objects with fewer visible pixels than min_visible_pixels are not annotated at all: an annotator
// would not have seen them.
// All numbers are rounded to two decimals, as in KITTI's files.
#ifndef STEREODET_SYNTH_LABELS_H_
#define STEREODET_SYNTH_LABELS_H_

#include <opencv2/core.hpp>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

struct LabelOptions {
  double visible_fraction_occluded_0 = 0.8;  // see the file comment
  double visible_fraction_occluded_1 = 0.4;
  double visible_fraction_occluded_2 = 0.1;
  // Thresholds for a 1242 x 375 image; scaled with the image size (heights with the image height,
  // pixel counts with its area).
  double min_visible_pixels = 40.0;
  double min_height_px = 18.0;          // smaller objects become DontCare
  double min_dontcare_height_px = 8.0;  // smaller DontCare regions are dropped
  double max_depth_m = 75.0;            // farther objects become DontCare
  // Silhouette samples per object for truncation and occlusion (a regular pixel grid over its box).
  int max_samples = 2500;
  double near_plane_m = 0.1;  // parts closer to the camera plane are clipped

  void Check() const;  // throws std::invalid_argument
};

// What the labeller measured for one scene object that projects into the image.
struct ObjectVisibility {
  int object = -1;                // Scene::objects index
  Box2D box;                      // amodal box, clipped to the image (not rounded)
  Box2D unclipped_box;            // amodal box before clipping
  double truncation = 0.0;        // fraction of the silhouette outside the image
  double visible_fraction = 0.0;  // of the in-image silhouette
  double visible_pixels = 0.0;    // estimated from the samples
};

// Measures every scene object whose silhouette reaches into the left image (camera 2), in
// Scene::objects order. `object_id` is the left render's id buffer (CV_32SC1, width x height).
std::vector<ObjectVisibility> MeasureVisibility(const Scene& scene, const Calibration& calib,
                                                const cv::Mat& object_id,
                                                const LabelOptions& options);

struct LabelSet {
  std::vector<Object> labels;  // labelled objects in Scene::objects order, then DontCare regions
  std::vector<int> source;     // Scene::objects index of each label
};

LabelSet MakeLabels(const Scene& scene, const Calibration& calib, const cv::Mat& object_id,
                    const LabelOptions& options = {});

}  // namespace stereodet

#endif  // STEREODET_SYNTH_LABELS_H_
