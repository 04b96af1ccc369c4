// model.json's shared parts as nlohmann::json, for the families' config readers and writers.
#ifndef STEREODET_MODELS_MODEL_JSON_INTERNAL_H_
#define STEREODET_MODELS_MODEL_JSON_INTERNAL_H_

#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/models/model_json.h"
#include "stereodet/util/check.h"

namespace stereodet::internal {

// j[field] as an int: a JSON integer in int's range. nlohmann's get<int>() would cast a float such
// as 1e300 (undefined behaviour) or cut a large integer silently. Throws ParseError naming
// `source` and `field`, nlohmann's exception when the field is missing.
int JsonInt(const nlohmann::json& j, const std::string& field, const std::string& source);

// j[field], a name, as the value `parse` (the family's Parse* of a name: std::optional) gives.
// Throws ParseError naming `source` and `field` when `parse` knows no such name ("unknown input
// encoding 'rgbd' (expected rgb, rgbh-fixed or rgbh-learned)": `what` and `names`), nlohmann's
// exception when the field is missing or not a string.
template <typename Parse>
auto JsonNamedValue(const nlohmann::json& j, const std::string& field, const std::string& source,
                    Parse parse, const std::string& what, const std::string& names) {
  const std::string name = j.at(field).get<std::string>();
  const auto parsed = parse(name);
  if (!parsed) {
    throw ParseError(source, 0, field,
                     "unknown " + what + " '" + name + "' (expected " + names + ")");
  }
  return *parsed;
}

// Every family's rule for its config's class names (KITTI's spelling): 1 to 256 names, each
// non-empty, without white space or commas (a label file's fields and the CLI's --classes lists).
// Throws std::invalid_argument naming the first bad one.
void CheckClassNames(const std::vector<std::string>& classes);

// A new model.json object: {"version": kModelConfigVersion, "architecture": architecture}.
nlohmann::json NewModelJson(const std::string& architecture);
// Adds `weights` as the "weights" object (nothing when its hash is empty) and, when given, the
// stereo settings as the "stereo" object; returns the text model.json holds (2-space indent, a
// final newline).
std::string FinishModelJson(nlohmann::json j, const WeightsRecord& weights,
                            const std::optional<StereoOptions>& stereo = std::nullopt);

// model.json's text parsed, its version checked and its architecture `architecture` ("ssd",
// "rpn", "det3d"). Throws ParseError naming `source` and the field ("not valid JSON", "unsupported
// version 2", "expected \"rpn\" (a model of `train rpn`)").
nlohmann::json ParseModelJson(const std::string& text, const std::string& source,
                              const std::string& architecture);

// A family's config read from model.json's fields (after ParseModelJson): `read(config, field)`
// fills `config`, setting `field` to each field's name before it reads it; then config.Check().
// A JSON error (a field missing or of another type) or a refused value (std::invalid_argument,
// from `read` or from Check()) becomes a ParseError naming `source` and that field.
template <typename Config, typename Read>
Config ReadConfigFields(const std::string& source, Read read) {
  std::string field;
  try {
    Config config;
    read(config, field);
    field.clear();
    config.Check();
    return config;
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, field, e.what());
  } catch (const std::invalid_argument& e) {
    throw ParseError(source, 0, field, e.what());
  }
}

}  // namespace stereodet::internal

#endif  // STEREODET_MODELS_MODEL_JSON_INTERNAL_H_
