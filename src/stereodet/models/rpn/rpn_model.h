// The late-fusion two-branch detector with a region proposal network (issue 15): ResNet-style
// trunks (residual blocks, batch norm) to stride 16; an image branch on R, G, B and, for RGB-D
// models, a geometry branch of its own on depth, height and validity (from block matching: the
// "point cloud in the image plane"); fused late, after the last stage, by concatenation and a 1x1
// convolution. The RGB model is the image branch alone. On the (fused) stride-16 features: a
// region proposal network (3x3 conv, objectness and box deltas per anchor), proposal NMS, RoIAlign
// (built on grid_sample), and a box head (two fully connected layers, softmax over background +
// classes, per-class box refinement). LibTorch is an implementation detail: nothing here exposes
// a torch type.
//
// A model folder holds model.json (RpnConfig, the WeightsRecord of model.pt, for RGB-D the stereo
// settings), model.pt, run.json, checkpoint.pt (training state for --resume) and train_log.csv.
#ifndef STEREODET_MODELS_RPN_RPN_MODEL_H_
#define STEREODET_MODELS_RPN_RPN_MODEL_H_

#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/models/box_coder.h"
#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/model_handle.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/rpn/rpn_boxes.h"
#include "stereodet/models/rpn/rpn_config.h"
#include "stereodet/models/trainer_handle.h"
#include "stereodet/stereo/rgbh.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

// The network input of one frame at the network's size. `bgr` is CV_8UC3 of the network size;
// `depth_code` and `height_code` CV_16UC1 of the same size (0 = no stereo), ignored for rgb.
// Channels, each in [0, 1]: R / 255, G / 255, B / 255, then for rgbd depth_code / max code,
// height_code / 511 and valid (1 where depth_code > 0, else 0: "no stereo" stays distinguishable
// from "near" and from "at ground level").
PlanarImage EncodeRpnInput(const cv::Mat& bgr, const cv::Mat& depth_code,
                           const cv::Mat& height_code, RpnInput input,
                           const DepthQuantization& depth = {});

struct RpnDetectOptions {
  ProposalOptions proposals{.pre_nms_top_n = 600, .nms_iou = 0.7, .post_nms_top_n = 100};
  RpnDecodeOptions decode;
  void Check() const;
};

// One training batch: the encoded inputs and each image's objects (network px; label >= 1 or
// kIgnoreLabel).
struct RpnBatch {
  std::vector<PlanarImage> inputs;
  std::vector<std::vector<TargetBox>> objects;
  // Each input's seed of its anchor and RoI sampling (train rpn: SampleSeed(step seed, 0, frame
  // index)); empty: SampleSeed(step seed, 0, position in the batch).
  std::vector<uint64_t> sampling_seeds;
};

namespace internal {
struct RpnModelImpl;
struct RpnTrainerImpl;
}  // namespace internal

// A new model from a config and a seed, Load, Save, config() and ParameterCount() are every
// family's (model_handle.h); model.json also records, for RGB-D models, the stereo settings.
// Not thread-safe: one thread at a time (LibTorch parallelises inside).
class RpnModel : public ModelHandle<RpnModel, RpnConfig, internal::RpnModelImpl> {
 public:
  using ModelHandle::ModelHandle;

  const StereoOptions& stereo() const;  // the depth/height settings (rgbd)
  void set_stereo(const StereoOptions& stereo);
  const std::vector<Box2D>& anchors() const;  // GenerateRpnAnchors of the feature map

  // Inference (evaluation-mode batch norm, no gradients): per input, boxes in network px, labels
  // >= 1, scores (softmax probabilities) in [0, 1], best first. Throws NonFiniteOutputError
  // (network_output.h) when an input's outputs hold a NaN or an inf (Propose too).
  std::vector<std::vector<ScoredBox>> Detect(const std::vector<PlanarImage>& inputs,
                                             const RpnDetectOptions& options = {}) const;
  // The proposals alone (label 0, score = objectness probability), per input.
  std::vector<std::vector<ScoredBox>> Propose(const std::vector<PlanarImage>& inputs,
                                              const ProposalOptions& options) const;

  int64_t ImageBranchParameterCount() const;
  int64_t GeometryBranchParameterCount() const;  // 0 for rgb

  // "Mirroring": copies the image branch, the RPN and the box head (and, with `geometry_too`, the
  // image branch into the geometry branch as well) from an RGB model of the same image width,
  // anchors, classes and head into this one. For an rgbd model the fusion keeps its own weights.
  // Returns the number of tensors copied. Throws std::invalid_argument when the shapes differ.
  int InitFrom(const RpnModel& rgb, bool geometry_too = false);

 private:
  friend class ModelHandle;  // Load makes one
  friend class RpnTrainer;
  friend struct internal::RpnTrainerImpl;
  using Impl = internal::RpnModelImpl;
};

struct RpnTrainerOptions {
  AnchorSamplingOptions anchors;
  ProposalOptions proposals;  // training: 1000 before NMS, 300 after
  RoiSamplingOptions rois;
  double weight_decay = 1e-4;  // AdamW
  void Check() const;
};

// The loss terms of one step (each a mean over its samples) and the sample counts over the batch.
struct RpnLossParts {
  double total = 0;
  double objectness = 0;  // RPN binary cross-entropy over the sampled anchors
  double rpn_box = 0;     // RPN smooth L1 over positive anchors / sampled anchors
  double head_class = 0;  // head cross-entropy over the sampled RoIs
  double head_box = 0;    // head smooth L1 (its class's deltas) over foreground / sampled RoIs
  int positive_anchors = 0;
  int foreground_rois = 0;
};

// Trains an RpnModel in place. SetGroup and the checkpoints are every family's
// (trainer_handle.h); with a group, the losses' counts (sampled anchors, sampled RoIs) are the
// whole batch's.
class RpnTrainer : public TrainerHandle<internal::RpnTrainerImpl> {
 public:
  RpnTrainer(RpnModel& model, const RpnTrainerOptions& options = {});
  // One optimizer step at `learning_rate`. Each image's anchor and RoI sampling draws from its own
  // stream (RpnBatch::sampling_seeds) and torch::manual_seed(step_seed) is set, so a step is a
  // function of the weights, the optimizer state, the batch and the seeds. Returns the loss before
  // the step (with a group, this rank's share of the whole batch's).
  RpnLossParts Step(const RpnBatch& batch, double learning_rate, uint64_t step_seed);
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_MODEL_H_
