// The two-stage detector's configuration (input, classes, input size, trunk widths, head, anchors)
// and model.json's text of it. Torch-free: the model_json fuzzer builds it with clang.
#ifndef STEREODET_MODELS_RPN_RPN_CONFIG_H_
#define STEREODET_MODELS_RPN_RPN_CONFIG_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/models/model_json.h"
#include "stereodet/models/rpn/rpn_boxes.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

enum class RpnInput {
  kRgb,   // the image branch alone
  kRgbd,  // image branch + geometry branch (depth, height, validity), fused late
};
const char* RpnInputName(RpnInput input);  // "rgb", "rgbd"
std::optional<RpnInput> ParseRpnInput(std::string_view text);
// Channels of the network input: 3 (R, G, B) or 6 (R, G, B, depth, height, valid).
int RpnInputChannels(RpnInput input);

struct RpnConfig {
  RpnInput input = RpnInput::kRgb;
  std::vector<std::string> classes = {"Car", "Pedestrian", "Cyclist"};
  // Network input size, px; multiples of 16 (the trunks' stride).
  int input_width = 640;
  int input_height = 192;
  // Base channels of each trunk (stages of base, 2 base, 4 base channels at strides 4, 8, 16;
  // ResNet-18 has 64): half width. A wider image branch (--image-width) is the control that gives
  // the RGB model the RGB-D model's parameter count.
  int image_width = 32;
  int geometry_width = 32;   // RGB-D only
  int blocks_per_stage = 2;  // residual blocks per stage (ResNet-18: 2)
  int head_channels = 256;   // the box head's fully connected layers
  int pooled_size = 7;       // RoIAlign output, cells per side
  int sampling_ratio = 2;    // RoIAlign samples per cell per side
  // Stride of the features the RPN and RoIAlign use: 16, or 8 (the third stage keeps the second's
  // resolution: finer cells for KITTI's small objects, at 4x the third stage's and the RPN's cost).
  int feature_stride = 16;
  AnchorOptions anchors;  // stride_px must equal feature_stride
  void Check() const;     // throws std::invalid_argument
  int NumClasses() const { return static_cast<int>(classes.size()); }  // without background
  int FeatureWidth() const { return input_width / feature_stride; }
  int FeatureHeight() const { return input_height / feature_stride; }
  // Channels of the features the RPN and the head see: 4 * image_width (the fusion reduces the
  // concatenated branches to that).
  int FeatureChannels() const { return 4 * image_width; }
};

// model.json's text (with `weights` when its fnv1a64 is set, and `stereo` when given), and back.
// Parse errors throw ParseError naming `source` and the field.
std::string RpnConfigToJson(const RpnConfig& config, const WeightsRecord& weights = {},
                            const std::optional<StereoOptions>& stereo = std::nullopt);
RpnConfig RpnConfigFromJson(const std::string& text, const std::string& source);
// The stereo settings model.json records (model_json.h's ReadStereoRecord, plus the depth code's
// range and bits); absent ones read as StereoOptions' defaults. Throws ParseError naming `source`.
StereoOptions ReadRpnStereoRecord(const std::string& text, const std::string& source);

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_CONFIG_H_
