// SsdConfig and its model.json text: torch-free, so the model_json fuzzer can build it.
#include "stereodet/models/ssd/ssd_config.h"

#include <nlohmann/json.hpp>

#include "stereodet/models/model_json_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

void SsdConfig::Check() const {
  boxes.Check();
  internal::CheckClassNames(classes);
  STEREODET_CHECK(boxes.num_maps == 4 && boxes.first_map_stride_log2 == 3)
      << "the SSD backbone has 4 feature maps from stride 8; got " << boxes.num_maps
      << " maps from stride " << (1 << boxes.first_map_stride_log2);
  STEREODET_CHECK(base_channels >= 4 && base_channels <= 256)
      << "base_channels must be in [4, 256], got " << base_channels;
}

std::string SsdConfigToJson(const SsdConfig& config, const WeightsRecord& weights,
                            const std::optional<StereoOptions>& stereo) {
  nlohmann::json j = internal::NewModelJson("ssd");
  j["encoding"] = InputEncodingName(config.encoding);
  j["classes"] = config.classes;
  j["input_width"] = config.boxes.input_width;
  j["input_height"] = config.boxes.input_height;
  j["num_maps"] = config.boxes.num_maps;
  j["first_map_stride_log2"] = config.boxes.first_map_stride_log2;
  j["min_size_fraction"] = config.boxes.min_size_fraction;
  j["aspect_ratios"] = config.boxes.aspect_ratios;
  j["base_channels"] = config.base_channels;
  return internal::FinishModelJson(std::move(j), weights, stereo);
}

SsdConfig SsdConfigFromJson(const std::string& text, const std::string& source) {
  const nlohmann::json j = internal::ParseModelJson(text, source, "ssd");
  return internal::ReadConfigFields<SsdConfig>(source, [&](SsdConfig& config, std::string& field) {
    field = "encoding";
    config.encoding = internal::JsonNamedValue(j, field, source, ParseInputEncoding,
                                               "input encoding", "rgb, rgbh-fixed or rgbh-learned");
    field = "classes";
    config.classes = j.at(field).get<std::vector<std::string>>();
    field = "input_width";
    config.boxes.input_width = internal::JsonInt(j, field, source);
    field = "input_height";
    config.boxes.input_height = internal::JsonInt(j, field, source);
    field = "num_maps";
    config.boxes.num_maps = internal::JsonInt(j, field, source);
    field = "first_map_stride_log2";
    config.boxes.first_map_stride_log2 = internal::JsonInt(j, field, source);
    field = "min_size_fraction";
    config.boxes.min_size_fraction = j.at(field).get<double>();
    field = "aspect_ratios";
    config.boxes.aspect_ratios = j.at(field).get<std::vector<double>>();
    field = "base_channels";
    config.base_channels = internal::JsonInt(j, field, source);
  });
}

}  // namespace stereodet
