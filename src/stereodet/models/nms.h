// Per-class greedy non-maximum suppression over plain boxes.
#ifndef STEREODET_MODELS_NMS_H_
#define STEREODET_MODELS_NMS_H_

#include <vector>

#include "stereodet/geometry/box.h"

namespace stereodet {

// A detection before it becomes a KITTI Object: a box, a score and a class index.
struct ScoredBox {
  Box2D box;        // px (whichever image the caller works in)
  float score = 0;  // higher is more confident
  int label = 0;    // class index; NMS never compares boxes of different labels
  bool operator==(const ScoredBox&) const = default;
};

struct NmsOptions {
  // A box is suppressed by a higher-scored kept box of the same label whose IoU with it is strictly
  // greater than this.
  double iou_threshold = 0.45;
  // Boxes scoring below this are dropped before NMS.
  float score_threshold = 0.0f;
  // Per label, only the this many highest-scored boxes enter NMS (0 = all). SSD's "top-k".
  int max_candidates_per_label = 0;
  // At most this many boxes are returned over all labels (0 = all).
  int max_detections = 0;

  void Check() const;  // throws std::invalid_argument
};

// Greedy NMS, label by label: boxes are visited from the highest score down (ties: earlier in the
// input first) and kept unless a kept box of the same label overlaps them by more than
// iou_threshold. Returns the kept boxes sorted by score, highest first (ties: input order), cut to
// max_detections.
std::vector<ScoredBox> NonMaximumSuppression(const std::vector<ScoredBox>& boxes,
                                             const NmsOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_NMS_H_
