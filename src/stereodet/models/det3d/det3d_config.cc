// Det3dConfig and its model.json text: torch-free (the model_json fuzzer builds it).
#include "stereodet/models/det3d/det3d_config.h"

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <utility>

#include "stereodet/models/model_json_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

void Det3dConfig::Check() const {
  grid.Check();
  internal::CheckClassNames(classes);
  STEREODET_CHECK(base_channels >= 4 && base_channels <= 256)
      << "base_channels must be in [4, 256], got " << base_channels;
  STEREODET_CHECK(max_points_per_pillar >= 1 && max_points_per_pillar <= 1024)
      << "max_points_per_pillar must be in [1, 1024], got " << max_points_per_pillar;
  STEREODET_CHECK(parts_l >= 1 && parts_l <= 8 && parts_w >= 1 && parts_w <= 8)
      << "the PSWarp part grid must be 1..8 x 1..8, got " << parts_l << " x " << parts_w;
}

std::vector<AnchorClass> Det3dConfig::AnchorClasses() const {
  std::vector<AnchorClass> out;
  for (const std::string& name : classes) out.push_back(DefaultAnchorClass(name));
  return out;
}

std::string Det3dConfigToJson(const Det3dConfig& config, const WeightsRecord& weights) {
  nlohmann::json j = internal::NewModelJson("det3d");
  j["input"] = PointSourceName(config.input);
  j["classes"] = config.classes;
  j["grid"] = {{"min_x_m", config.grid.min_x_m},  {"max_x_m", config.grid.max_x_m},
               {"min_y_m", config.grid.min_y_m},  {"max_y_m", config.grid.max_y_m},
               {"min_z_m", config.grid.min_z_m},  {"max_z_m", config.grid.max_z_m},
               {"pillar_m", config.grid.pillar_m}};
  j["base_channels"] = config.base_channels;
  j["max_points_per_pillar"] = config.max_points_per_pillar;
  j["parts_l"] = config.parts_l;
  j["parts_w"] = config.parts_w;
  return internal::FinishModelJson(std::move(j), weights);
}

Det3dConfig Det3dConfigFromJson(const std::string& text, const std::string& source) {
  const nlohmann::json j = internal::ParseModelJson(text, source, "det3d");
  return internal::ReadConfigFields<Det3dConfig>(
      source, [&](Det3dConfig& config, std::string& field) {
        field = "input";
        config.input = internal::JsonNamedValue(j, field, source, ParsePointSource, "input",
                                                "lidar or stereo");
        field = "classes";
        config.classes = j.at(field).get<std::vector<std::string>>();
        const nlohmann::json& g = j.at("grid");
        for (auto [name, value] : std::initializer_list<std::pair<const char*, double*>>{
                 {"min_x_m", &config.grid.min_x_m},
                 {"max_x_m", &config.grid.max_x_m},
                 {"min_y_m", &config.grid.min_y_m},
                 {"max_y_m", &config.grid.max_y_m},
                 {"min_z_m", &config.grid.min_z_m},
                 {"max_z_m", &config.grid.max_z_m},
                 {"pillar_m", &config.grid.pillar_m}}) {
          field = std::string("grid.") + name;
          *value = g.at(name).get<double>();
        }
        field = "base_channels";
        config.base_channels = internal::JsonInt(j, field, source);
        field = "max_points_per_pillar";
        config.max_points_per_pillar = internal::JsonInt(j, field, source);
        field = "parts_l";
        config.parts_l = internal::JsonInt(j, field, source);
        field = "parts_w";
        config.parts_w = internal::JsonInt(j, field, source);
      });
}

}  // namespace stereodet
