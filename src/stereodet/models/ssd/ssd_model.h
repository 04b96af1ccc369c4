// The single-shot detector (SSD) on one image-like input, as in the paper's RGB vs RGB-H study: a
// small convolutional backbone, four feature maps (strides 8, 16, 32, 64 px), 3x3 convolutional
// heads giving per default box class scores and box offsets, MultiBox loss with 3:1 hard negative
// mining, per-class NMS. LibTorch is an implementation detail: nothing here exposes a torch type.
//
// A model folder holds:
//   model.json      the SsdConfig (input encoding, classes, input size, default boxes, width),
//                   the hash, input channels and parameter count of its model.pt (WeightsRecord)
//                   and, for RGB-H models, the stereo settings its heights were made with
//   model.pt        the weights (LibTorch archive)
//   run.json        the run manifest (util/run_manifest.h): command line, version, data, settings
//   checkpoint.pt   training state for --resume (weights, optimizer, epochs done, the config and
//                   the training run it was written by); not needed to detect
//   train_log.csv   one line per epoch (ssd_train.h)
#ifndef STEREODET_MODELS_SSD_SSD_MODEL_H_
#define STEREODET_MODELS_SSD_SSD_MODEL_H_

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/models/box_coder.h"
#include "stereodet/models/default_boxes.h"
#include "stereodet/models/device.h"
#include "stereodet/models/distributed.h"
#include "stereodet/models/model_handle.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/ssd/input_encoding.h"
#include "stereodet/models/ssd/ssd_config.h"
#include "stereodet/models/trainer_handle.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

// Raw network outputs for a batch, row-major: deltas [image][default box][4], probabilities
// [image][default box][class] (softmax over background + classes).
struct SsdOutputs {
  int num_images = 0;
  int num_boxes = 0;
  int num_classes = 0;  // with background
  std::vector<float> deltas;
  std::vector<float> probabilities;
};

// One training batch as plain arrays (built by ssd_data.h's loader, consumed by SsdTrainer).
struct TrainBatch {
  int batch_size = 0, channels = 0, height = 0, width = 0;
  std::vector<float> images;    // [batch][channel][row][column], the encoded inputs
  std::vector<int64_t> labels;  // [batch][default box]: 0 background, >= 1 class, kIgnoreLabel
  std::vector<float> deltas;    // [batch][default box][4]: box targets (box_coder.h) for positives
  int num_positive = 0;         // over the batch
};

namespace internal {
struct SsdModelImpl;
}  // namespace internal

// A new model from a config and a seed, Load, Save, config() and ParameterCount() are every
// family's (model_handle.h); model.json also records, for RGB-H models, the stereo settings.
// Not thread-safe: one thread at a time may call Forward/Detect (LibTorch parallelises inside).
class SsdModel : public ModelHandle<SsdModel, SsdConfig, internal::SsdModelImpl> {
 public:
  using ModelHandle::ModelHandle;

  // The stereo settings the model's heights are made with (RGB-H): those of model.json after Load,
  // StereoOptions' defaults for a new model until set_stereo. Unused by rgb models.
  const StereoOptions& stereo() const;
  void set_stereo(const StereoOptions& stereo);
  // The default boxes, in the order of the outputs' box dimension.
  const std::vector<DefaultBox>& default_boxes() const;

  // Inference (no gradients, batch norm in evaluation mode). Requires: each input has
  // NetworkInputChannels(config().encoding) planes of the config's input size (EncodeNetworkInput).
  // Throws NonFiniteOutputError (network_output.h) when an input's outputs hold a NaN or an inf.
  SsdOutputs Forward(const std::vector<PlanarImage>& inputs) const;
  // Forward + DecodeDetections: per input, boxes in network-input px, labels >= 1, best first.
  std::vector<std::vector<ScoredBox>> Detect(const std::vector<PlanarImage>& inputs,
                                             const DecodeOptions& options = {}) const;

  // Trainable parameters of the learned 1x1 colour compression alone (0 unless rgbh-learned: 3 x 2
  // weights, no bias, = 6).
  int64_t CompressionParameterCount() const;
  // Multiply-accumulates of one forward pass on one image (convolutions; FLOPs ~ 2x this).
  int64_t MultiplyAccumulates() const;

 private:
  friend class ModelHandle;  // Load makes one
  friend class SsdTrainer;
  using Impl = internal::SsdModelImpl;
};

struct MultiBoxLossOptions {
  // Hard negative mining: per image, the negatives with the highest background loss are kept, at
  // most negative_ratio per positive (SSD's 3:1) ...
  double negative_ratio = 3.0;
  // ... and at least this many, so frames without objects still teach "background".
  int min_negatives_per_image = 8;
  // Weight of the smooth-L1 box loss against the softmax cross-entropy.
  double localization_weight = 1.0;
  void Check() const;
};

struct SsdTrainerOptions {
  MultiBoxLossOptions loss;
  // AdamW; the learning rate is given per step (the schedule lives in ssd_train.cc).
  double weight_decay = 5e-4;
  void Check() const;
};

// The loss terms of one step, each divided by the number of positives (at least 1).
struct LossParts {
  double total = 0;
  double localization = 0;
  double confidence = 0;
  int num_positive = 0;
};

namespace internal {
struct SsdTrainerImpl;
}  // namespace internal

// Trains an SsdModel in place: holds the optimizer state. SetGroup and the checkpoints are every
// family's (trainer_handle.h); the checkpoint's config is SsdConfigToJson's (encoding, classes,
// input size, boxes, width).
class SsdTrainer : public TrainerHandle<internal::SsdTrainerImpl> {
 public:
  // `model` must outlive the trainer.
  SsdTrainer(SsdModel& model, const SsdTrainerOptions& options = {});

  // One optimizer step on `batch` at `learning_rate`. Returns the loss before the step (with a
  // group, this rank's share of the whole batch's: its terms add up over the ranks).
  LossParts Step(const TrainBatch& batch, double learning_rate);
  // The loss on `batch` without changing anything (training-mode batch norm is not used: evaluation
  // mode, no gradients).
  LossParts Evaluate(const TrainBatch& batch) const;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_SSD_MODEL_H_
