// What every family's model.json shares (its config is the family's own): the file names, the
// format version, the "weights" record that ties model.json to its model.pt, and the "stereo"
// settings of the models whose input is made by stereo matching. Torch-free.
#ifndef STEREODET_MODELS_MODEL_JSON_H_
#define STEREODET_MODELS_MODEL_JSON_H_

#include <cstdint>
#include <string>

#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

// The files of a model folder that detecting needs (the training's others: train_common.h).
inline constexpr char kModelConfigFile[] = "model.json";
inline constexpr char kModelWeightsFile[] = "model.pt";
// model.json's "version" that this build reads and writes.
inline constexpr int kModelConfigVersion = 1;

// What model.json records about its model.pt, so that weights from another training (another
// input, other shapes) are refused instead of loading silently.
struct WeightsRecord {
  std::string fnv1a64;      // FNV-1a 64 of model.pt's bytes, 16 hex digits; empty = not recorded
  int input_channels = 0;   // the network's input channels (the family's encoding of its input)
  int64_t parameters = -1;  // the model's ParameterCount(); -1 = not recorded
  // The training run that wrote model.pt, 16 hex digits; its checkpoint.pt records the same, so
  // --resume refuses a checkpoint copied from another folder. Empty = not recorded.
  std::string training_run;
};

// model.json's "weights" object {file, fnv1a64, input_channels, parameters, training_run}; an
// empty record when the text has none (a model.json written before weights were recorded). Throws
// ParseError naming `source` and the field.
WeightsRecord ReadWeightsRecord(const std::string& text, const std::string& source);

// The stereo settings model.json records (StereoSettingsJson's disparity, ground, height_code); a
// setting (or the whole "stereo" object: image-only models, model.json written before session 5)
// that is absent reads as StereoOptions' documented default. Throws ParseError naming `source` and
// the key for a bad value.
StereoOptions ReadStereoRecord(const std::string& text, const std::string& source);

}  // namespace stereodet

#endif  // STEREODET_MODELS_MODEL_JSON_H_
