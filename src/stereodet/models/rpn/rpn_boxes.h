// The torch-free box arithmetic of the two-stage detector (region proposal network + box head, as
// in Faster R-CNN): anchors on the stride-16 feature map, the box coding of both stages, the
// sampling of anchors and RoIs for training, proposal selection (models/nms) and the decoding of
// the box head into per-class detections. Every box is in network-input px.
#ifndef STEREODET_MODELS_RPN_RPN_BOXES_H_
#define STEREODET_MODELS_RPN_RPN_BOXES_H_

#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include "stereodet/geometry/box.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/models/nms.h"

namespace stereodet {

struct AnchorOptions {
  int stride_px = 16;  // of the feature map the RPN runs on (the trunks' last stage)
  // Anchor sizes, sqrt(width * height) in network-input px. At the default input (640 x 192, about
  // half of KITTI's 1242 x 375) KITTI's evaluated objects (>= 25 px tall) are 13..190 px tall.
  std::vector<double> sizes_px = {16.0, 32.0, 64.0, 128.0};
  // Height / width: 0.5 cars seen from the side, 1 cars from behind, 2 pedestrians and cyclists.
  std::vector<double> ratios = {0.5, 1.0, 2.0};
  void Check() const;  // throws std::invalid_argument
  int AnchorsPerCell() const { return static_cast<int>(sizes_px.size() * ratios.size()); }
};

// Anchors of a map_width x map_height feature map, in the order [row][column][size][ratio] (the
// order of the RPN's outputs). The anchor of cell (row, column), size s and ratio r is centred on
// ((column + 0.5) * stride, (row + 0.5) * stride), width s / sqrt(r), height s * sqrt(r).
std::vector<Box2D> GenerateRpnAnchors(int map_width, int map_height, const AnchorOptions& options);

// Faster R-CNN's box coding relative to a reference box: d = (wx (cx - rcx) / rw, wy (cy - rcy) /
// rh, ww log(w / rw), wh log(h / rh)). The RPN uses weights 1, the box head 10, 10, 5, 5.
struct DeltaWeights {
  double x = 1.0, y = 1.0, w = 1.0, h = 1.0;
};
inline constexpr DeltaWeights kHeadDeltaWeights{10.0, 10.0, 5.0, 5.0};

// Requires: both boxes with positive width and height.
std::array<float, 4> EncodeDeltas(const Box2D& box, const Box2D& reference,
                                  const DeltaWeights& weights = {});
// Inverse of EncodeDeltas; the size deltas are clamped to log(1000 / 16) so that exp() stays
// finite.
Box2D DecodeDeltas(const float* deltas, const Box2D& reference, const DeltaWeights& weights = {});

struct AnchorSamplingOptions {
  double positive_iou = 0.7;  // an anchor overlapping an object this much is positive ...
  double negative_iou = 0.3;  // ... one overlapping every object less is negative ...
  // ... unless it overlaps an ignore region (kIgnoreLabel) at least this much. Besides, each object
  // claims the anchors of its highest IoU (ties included) as positives.
  double ignore_iou = 0.5;
  int samples_per_image = 256;     // anchors in the loss per image ...
  double positive_fraction = 0.5;  // ... at most this fraction positive (the rest negative)
  void Check() const;
};

// Per anchor: 1 sampled positive, 0 sampled negative, -1 not in the loss.
struct RpnAnchorTargets {
  std::vector<int8_t> labels;
  std::vector<float> deltas;  // 4 per anchor (RPN coding, weights 1); zeros unless positive
  int num_positive = 0;
  int num_negative = 0;
};

// Assigns and samples the anchors of one image: positives and negatives as AnchorSamplingOptions
// says, then at most samples_per_image * positive_fraction positives and samples_per_image minus
// the positives kept negatives, each a uniform random subset drawn from `rng`. Objects with an
// empty box are skipped.
RpnAnchorTargets SampleAnchors(const std::vector<Box2D>& anchors,
                               const std::vector<TargetBox>& objects,
                               const AnchorSamplingOptions& options, std::mt19937_64& rng);

struct ProposalOptions {
  int pre_nms_top_n = 1000;  // highest-scored anchors decoded into candidates
  double nms_iou = 0.7;      // NMS among them
  int post_nms_top_n = 300;  // proposals kept
  double min_size_px = 2.0;  // proposals narrower or lower than this are dropped
  void Check() const;
};

// One image's proposals: anchors decoded by `deltas` (4 per anchor, RPN coding), clipped to the
// image (width x height px), too small ones dropped, the pre_nms_top_n of highest objectness
// `scores` (one per anchor) through NMS, the post_nms_top_n best kept. Label 0, score = objectness.
std::vector<ScoredBox> SelectProposals(const float* scores, const float* deltas,
                                       const std::vector<Box2D>& anchors, int image_width,
                                       int image_height, const ProposalOptions& options);

struct RoiSamplingOptions {
  double foreground_iou = 0.5;  // a RoI overlapping an object this much is foreground (its class)
  double background_iou = 0.5;  // one overlapping every object less is background ...
  double ignore_iou = 0.5;      // ... unless it overlaps an ignore region this much (then dropped)
  int samples_per_image = 128;  // RoIs in the head's loss per image ...
  double foreground_fraction = 0.25;  // ... at most this fraction foreground
  void Check() const;
};

// The RoIs of one image for the box head's loss.
struct RoiTargets {
  std::vector<Box2D> rois;
  std::vector<int64_t> labels;  // 0 background, >= 1 class
  std::vector<float> deltas;    // 4 per RoI (kHeadDeltaWeights) towards its object; zeros if bg
  int num_foreground = 0;
};

// Samples RoIs among the proposals and the objects' own boxes (label >= 1, always candidates, so
// the head sees foreground from the first step on): foreground first (uniform random subset of at
// most samples_per_image * foreground_fraction), then background up to samples_per_image.
RoiTargets SampleRois(const std::vector<ScoredBox>& proposals,
                      const std::vector<TargetBox>& objects, const RoiSamplingOptions& options,
                      std::mt19937_64& rng);

struct RpnDecodeOptions {
  // Per-class probability (softmax over background + classes) below which a RoI is not a
  // detection of that class.
  float score_threshold = 0.01f;
  NmsOptions nms{.iou_threshold = 0.45,
                 .score_threshold = 0.0f,
                 .max_candidates_per_label = 200,
                 .max_detections = 100};
  void Check() const;
};

// The box head's outputs of one image into detections: for RoI i and class k >= 1, the box
// DecodeDeltas(deltas + (i * num_classes + k - 1) * 4, rois[i], kHeadDeltaWeights) clipped to the
// image, scored probabilities[i * (num_classes + 1) + k]; per-class NMS. `num_classes` excludes
// background. Returns labels >= 1, best first.
std::vector<ScoredBox> DecodeRpnDetections(const std::vector<Box2D>& rois,
                                           const float* probabilities, const float* deltas,
                                           int num_classes, int image_width, int image_height,
                                           const RpnDecodeOptions& options);

// The first `k` of a uniform random permutation of 0..n-1 drawn from `rng` (Fisher-Yates with our
// own index draws: std::shuffle's algorithm differs between standard libraries).
std::vector<int> RandomSubset(int n, int k, std::mt19937_64& rng);

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_BOXES_H_
