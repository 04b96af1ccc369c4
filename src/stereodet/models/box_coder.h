// SSD box encoding (ground truth -> regression targets relative to default boxes), matching of
// ground truth to default boxes, and decoding of network outputs into scored boxes.
//
// All boxes are in network-input pixels (see default_boxes.h).
#ifndef STEREODET_MODELS_BOX_CODER_H_
#define STEREODET_MODELS_BOX_CODER_H_

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "stereodet/geometry/box.h"
#include "stereodet/kitti/object.h"
#include "stereodet/models/default_boxes.h"
#include "stereodet/models/nms.h"

namespace stereodet {

// SSD's encoding: d = ((cx - pcx) / pw / vc, (cy - pcy) / ph / vc, log(w / pw) / vs, log(h / ph) /
// vs) with the "variances" vc, vs scaling the targets to roughly unit spread.
struct BoxCoderOptions {
  float center_variance = 0.1f;
  float size_variance = 0.2f;
  void Check() const;
};

// Requires: box and prior with positive width and height.
std::array<float, 4> EncodeBox(const Box2D& box, const DefaultBox& prior,
                               const BoxCoderOptions& options = {});
// Inverse of EncodeBox. Size deltas are clamped to log(1000) / size_variance so exp() stays finite.
Box2D DecodeBox(const float* deltas, const DefaultBox& prior, const BoxCoderOptions& options = {});

// A ground-truth box for training: `label` >= 1 is a class (index into the model's classes plus
// one; 0 is background), kIgnoreLabel marks a region to ignore (DontCare, Van for Car, an object
// mostly cut away by augmentation).
inline constexpr int64_t kIgnoreLabel = -1;
struct TargetBox {
  Box2D box;  // px
  int64_t label = 0;
};

struct MatchOptions {
  // A default box whose best IoU with an object is >= this is a positive for that object. Every
  // object also claims the default box that overlaps it best (so no object goes unmatched, unless
  // it overlaps no default box at all).
  double positive_iou = 0.5;
  // A default box that is not positive and overlaps an ignore region by >= this is ignored: neither
  // positive nor negative in the loss.
  double ignore_iou = 0.5;
  BoxCoderOptions coder;
  void Check() const;
};

struct MatchResult {
  std::vector<int64_t> labels;  // per default box: 0 background, >= 1 class, kIgnoreLabel
  std::vector<float> deltas;    // 4 per default box (zeros unless positive)
  int num_positive = 0;
};

// SSD's matching of objects (label >= 1) and ignore regions (kIgnoreLabel) to default boxes.
// Objects with an empty box are skipped.
MatchResult MatchDefaultBoxes(const std::vector<DefaultBox>& priors,
                              const std::vector<TargetBox>& objects, const MatchOptions& options);

struct DecodeOptions {
  // Per-class score (softmax probability) below which a default box is not considered.
  float score_threshold = 0.01f;
  NmsOptions nms{.iou_threshold = 0.45,
                 .score_threshold = 0.0f,
                 .max_candidates_per_label = 200,
                 .max_detections = 100};
  BoxCoderOptions coder;
  void Check() const;
};

// Turns one image's outputs into detections: `deltas` holds 4 floats per default box,
// `probabilities` num_classes floats per default box (softmax over background + classes, background
// at index 0). Returns boxes (network-input px, not clipped) with label = class index >= 1, after
// per-class NMS, highest score first.
std::vector<ScoredBox> DecodeDetections(const float* deltas, const float* probabilities,
                                        int num_classes, const std::vector<DefaultBox>& priors,
                                        const DecodeOptions& options);

// Network-input boxes -> KITTI detections in the original image: scaled by (scale_x, scale_y),
// clipped to [0, image_width] x [0, image_height], rounded to 0.01 px, empty boxes dropped, score
// rounded to 1e-6, type = classes[label - 1],
// truncated and occluded -1 (unknown), 3D fields "not estimated" (Object::SetNot3DEstimated), score
// kept. Order kept (best first).
std::vector<Object> ToKittiDetections(const std::vector<ScoredBox>& boxes,
                                      const std::vector<std::string>& classes, double scale_x,
                                      double scale_y, int image_width, int image_height);

}  // namespace stereodet

#endif  // STEREODET_MODELS_BOX_CODER_H_
