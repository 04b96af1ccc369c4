// The single-stage 3D detector (issue 14): SA-SSD's ideas (He et al. 2020) on a dense pillar / BEV
// backbone, as no sparse convolution is available. LibTorch stays inside det3d_model.cc.
//
//   points --Pillarize--> pillar feature net (linear + BN + ReLU, max over a pillar's points)
//   --scatter--> BEV canvas [C, rows, cols] --> 3 conv blocks (strides 2, 4, 8 of the canvas)
//   --> upsampled to stride 2 and concatenated --> 1x1 heads per anchor: class logit, 7 box
//   residuals, 2 direction logits; and part-sensitive class maps (PSWarp).
//   Training only: the auxiliary network samples the 3 blocks' maps bilinearly at each point
//   (plus its height) and predicts foreground and the offset to its box's centre.
//   Score = mean of sigmoid(class logit) and the PSWarp confidence (the part maps sampled at the
//   predicted box's part centres, averaged, sigmoid).
//
// A model folder is every family's (model_json.h): model.json (Det3dConfig + weights record),
// model.pt, run.json, checkpoint.pt, train_log.csv.
#ifndef STEREODET_MODELS_DET3D_DET3D_MODEL_H_
#define STEREODET_MODELS_DET3D_DET3D_MODEL_H_

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "stereodet/models/det3d/det3d_config.h"
#include "stereodet/models/det3d/det3d_data.h"
#include "stereodet/models/det3d/det3d_targets.h"
#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/model_handle.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/trainer_handle.h"

namespace stereodet {

// One frame's network input and (training) targets.
struct Det3dSample {
  Pillars pillars;
  AnchorTargets anchors;       // training only
  PointTargets points;         // training only, for aux_xyz
  std::vector<float> aux_xyz;  // [point][3] the auxiliary network's points (a subsample)
};

// Builds a frame's sample: pillars, and with `with_targets` the anchor and auxiliary targets
// (at most `max_aux_points` points, an even subsample).
Det3dSample MakeDet3dSample(const Det3dFrame& frame, const Det3dConfig& config,
                            const std::vector<LidarBox>& anchors, bool with_targets,
                            int max_aux_points = 4096);

struct Det3dLossParts {
  double total = 0, classification = 0, box = 0, direction = 0, part_warp = 0, segmentation = 0,
         centre = 0;
  int num_positive = 0;
};

struct Det3dDecodeOptions {
  float score_threshold = 0.1f;
  RotatedNmsOptions nms;  // BEV IoU 0.1, 1000 candidates, at most 100 boxes a frame
  void Check() const;
};

namespace internal {
struct Det3dModelImpl;
struct Det3dTrainerImpl;
}  // namespace internal

// A new model from a config and a seed, Load, Save, config() and ParameterCount() are every
// family's (model_handle.h). Not thread-safe: one thread at a time.
class Det3dModel : public ModelHandle<Det3dModel, Det3dConfig, internal::Det3dModelImpl> {
 public:
  using ModelHandle::ModelHandle;

  const std::vector<LidarBox>& anchors() const;
  ComputeDevice device() const;

  // Inference (no gradients, BN in evaluation mode; the auxiliary network is not run): per sample,
  // scored boxes after rotated NMS, best first. Throws NonFiniteOutputError (network_output.h)
  // when a sample's outputs hold a NaN or an inf.
  std::vector<std::vector<ScoredLidarBox>> Detect(const std::vector<Det3dSample>& samples,
                                                  const Det3dDecodeOptions& options = {}) const;

  int64_t AuxiliaryParameterCount() const;  // of the auxiliary network (unused at inference)

 private:
  friend class ModelHandle;  // Load makes one
  friend class Det3dTrainer;
  using Impl = internal::Det3dModelImpl;
};

struct Det3dLossOptions {
  double box_weight = 2.0;        // SA-SSD's omega
  double direction_weight = 0.2;  // SECOND
  double part_warp_weight = 1.0;
  double segmentation_weight = 0.9;  // SA-SSD's mu
  double centre_weight = 2.0;        // SA-SSD's lambda
  bool auxiliary = true;             // train the auxiliary network
  void Check() const;
};

// Trains a Det3dModel in place. SetGroup and the checkpoints are every family's
// (trainer_handle.h).
class Det3dTrainer : public TrainerHandle<internal::Det3dTrainerImpl> {
 public:
  Det3dTrainer(Det3dModel& model, const Det3dLossOptions& loss = {}, double weight_decay = 1e-2);
  // One optimizer step; with a group, the loss returned is this rank's share of the whole batch's.
  Det3dLossParts Step(const std::vector<Det3dSample>& batch, double learning_rate);
  Det3dLossParts Evaluate(const std::vector<Det3dSample>& batch) const;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_MODEL_H_
