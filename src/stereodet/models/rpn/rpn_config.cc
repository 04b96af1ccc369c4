// RpnConfig, the input kinds and model.json's text: torch-free (the model_json fuzzer builds it).
#include "stereodet/models/rpn/rpn_config.h"

#include <nlohmann/json.hpp>

#include "stereodet/models/model_json_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

constexpr int kStride = 16;

}  // namespace

const char* RpnInputName(RpnInput input) { return input == RpnInput::kRgbd ? "rgbd" : "rgb"; }

std::optional<RpnInput> ParseRpnInput(std::string_view text) {
  if (text == "rgb") return RpnInput::kRgb;
  if (text == "rgbd") return RpnInput::kRgbd;
  return std::nullopt;
}

int RpnInputChannels(RpnInput input) { return input == RpnInput::kRgbd ? 6 : 3; }

void RpnConfig::Check() const {
  anchors.Check();
  internal::CheckClassNames(classes);
  STEREODET_CHECK(input_width >= kStride && input_height >= kStride && input_width % kStride == 0 &&
                  input_height % kStride == 0 && input_width <= 4096 && input_height <= 4096)
      << "the input size must be a multiple of 16 px in [16, 4096], got " << input_width << " x "
      << input_height;
  STEREODET_CHECK(image_width >= 2 && image_width <= 256)
      << "image_width must be in [2, 256], got " << image_width;
  STEREODET_CHECK(geometry_width >= 2 && geometry_width <= 256)
      << "geometry_width must be in [2, 256], got " << geometry_width;
  STEREODET_CHECK(blocks_per_stage >= 1 && blocks_per_stage <= 8)
      << "blocks_per_stage must be in [1, 8], got " << blocks_per_stage;
  STEREODET_CHECK(head_channels >= 4 && head_channels <= 4096)
      << "head_channels must be in [4, 4096], got " << head_channels;
  STEREODET_CHECK(pooled_size >= 1 && pooled_size <= 16)
      << "pooled_size must be in [1, 16], got " << pooled_size;
  STEREODET_CHECK(sampling_ratio >= 1 && sampling_ratio <= 8)
      << "sampling_ratio must be in [1, 8], got " << sampling_ratio;
  STEREODET_CHECK(feature_stride == 8 || feature_stride == 16)
      << "feature_stride must be 8 or 16, got " << feature_stride;
  STEREODET_CHECK(anchors.stride_px == feature_stride)
      << "the anchors' stride (" << anchors.stride_px << ") must be the feature stride ("
      << feature_stride << ")";
}

std::string RpnConfigToJson(const RpnConfig& config, const WeightsRecord& weights,
                            const std::optional<StereoOptions>& stereo) {
  nlohmann::json j = internal::NewModelJson("rpn");
  j["input"] = RpnInputName(config.input);
  j["classes"] = config.classes;
  j["input_width"] = config.input_width;
  j["input_height"] = config.input_height;
  j["image_width"] = config.image_width;
  j["geometry_width"] = config.geometry_width;
  j["blocks_per_stage"] = config.blocks_per_stage;
  j["head_channels"] = config.head_channels;
  j["pooled_size"] = config.pooled_size;
  j["sampling_ratio"] = config.sampling_ratio;
  j["feature_stride"] = config.feature_stride;
  j["anchor_sizes_px"] = config.anchors.sizes_px;
  j["anchor_ratios"] = config.anchors.ratios;
  if (stereo) {
    j["depth_code"] = {{"min_m", stereo->depth.min_m},
                       {"max_m", stereo->depth.max_m},
                       {"bits", stereo->depth.bits}};
  }
  return internal::FinishModelJson(std::move(j), weights, stereo);
}

RpnConfig RpnConfigFromJson(const std::string& text, const std::string& source) {
  const nlohmann::json j = internal::ParseModelJson(text, source, "rpn");
  return internal::ReadConfigFields<RpnConfig>(source, [&](RpnConfig& config, std::string& field) {
    field = "input";
    config.input =
        internal::JsonNamedValue(j, field, source, ParseRpnInput, "input", "rgb or rgbd");
    field = "classes";
    config.classes = j.at(field).get<std::vector<std::string>>();
    for (auto [name, target] : {std::pair<const char*, int*>{"input_width", &config.input_width},
                                {"input_height", &config.input_height},
                                {"image_width", &config.image_width},
                                {"geometry_width", &config.geometry_width},
                                {"blocks_per_stage", &config.blocks_per_stage},
                                {"head_channels", &config.head_channels},
                                {"pooled_size", &config.pooled_size},
                                {"sampling_ratio", &config.sampling_ratio}}) {
      field = name;
      *target = internal::JsonInt(j, field, source);
    }
    field = "feature_stride";  // absent: 16, the only stride before it was recorded
    config.feature_stride = j.contains(field) ? internal::JsonInt(j, field, source) : 16;
    config.anchors.stride_px = config.feature_stride;
    field = "anchor_sizes_px";
    config.anchors.sizes_px = j.at(field).get<std::vector<double>>();
    field = "anchor_ratios";
    config.anchors.ratios = j.at(field).get<std::vector<double>>();
  });
}

StereoOptions ReadRpnStereoRecord(const std::string& text, const std::string& source) {
  StereoOptions stereo = ReadStereoRecord(text, source);
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_object() && j.contains("depth_code")) {
    try {
      stereo.depth.min_m = j["depth_code"].at("min_m").get<double>();
      stereo.depth.max_m = j["depth_code"].at("max_m").get<double>();
      stereo.depth.bits = internal::JsonInt(j["depth_code"], "bits", source);
      stereo.depth.Check();
    } catch (const std::exception& e) {
      throw ParseError(source, 0, "depth_code", e.what());
    }
  }
  return stereo;
}

}  // namespace stereodet
