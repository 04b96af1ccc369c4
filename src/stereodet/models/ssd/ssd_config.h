// The single-shot detector's configuration (input encoding, classes, input size, default boxes,
// width) and model.json's text of it. Torch-free: the model_json fuzzer builds it with clang.
#ifndef STEREODET_MODELS_SSD_SSD_CONFIG_H_
#define STEREODET_MODELS_SSD_SSD_CONFIG_H_

#include <optional>
#include <string>
#include <vector>

#include "stereodet/models/default_boxes.h"
#include "stereodet/models/model_json.h"
#include "stereodet/models/ssd/input_encoding.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

struct SsdConfig {
  InputEncoding encoding = InputEncoding::kRgb;
  // Class names in KITTI's spelling; the network's class index i >= 1 is classes[i - 1], 0 is
  // background.
  std::vector<std::string> classes = {"Car", "Pedestrian", "Cyclist"};
  // Input size and default boxes. The backbone fixes 4 maps starting at stride 8.
  DefaultBoxOptions boxes;
  // Backbone width: its stages have base, 2, 4 and 8 times base channels (ssd_net.cc).
  int base_channels = 16;

  void Check() const;  // throws std::invalid_argument
  int NumClassesWithBackground() const { return static_cast<int>(classes.size()) + 1; }
  int InputWidth() const { return boxes.input_width; }
  int InputHeight() const { return boxes.input_height; }
};

// JSON text of a config, and back. Parse errors throw ParseError naming `source`. With a
// non-empty `weights.fnv1a64` the text has a "weights" object {file, fnv1a64, input_channels,
// parameters, and training_run when not empty}, which SsdConfigFromJson ignores and
// ReadWeightsRecord (model_json.h) reads. With `stereo` the text has a "stereo" object,
// which ReadStereoRecord reads.
std::string SsdConfigToJson(const SsdConfig& config, const WeightsRecord& weights = {},
                            const std::optional<StereoOptions>& stereo = std::nullopt);
SsdConfig SsdConfigFromJson(const std::string& text, const std::string& source);

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_SSD_CONFIG_H_
