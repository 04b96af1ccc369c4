#include "stereodet/models/model_json.h"

#include <cstdint>
#include <limits>

#include "stereodet/models/model_json_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

nlohmann::json ParseJsonText(const std::string& text, const std::string& source) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, "", std::string("not valid JSON: ") + e.what());
  }
}

}  // namespace

namespace internal {

int JsonInt(const nlohmann::json& j, const std::string& field, const std::string& source) {
  const nlohmann::json& value = j.at(field);
  if (!value.is_number_integer()) {
    throw ParseError(source, 0, field, "expected an integer, got " + value.dump().substr(0, 40));
  }
  const bool in_range =
      value.is_number_unsigned()
          ? value.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<int>::max())
          : value.get<int64_t>() >= std::numeric_limits<int>::min() &&
                value.get<int64_t>() <= std::numeric_limits<int>::max();
  if (!in_range) throw ParseError(source, 0, field, value.dump() + " is out of range");
  return value.is_number_unsigned() ? static_cast<int>(value.get<uint64_t>())
                                    : static_cast<int>(value.get<int64_t>());
}

void CheckClassNames(const std::vector<std::string>& classes) {
  STEREODET_CHECK(!classes.empty() && classes.size() <= 256)
      << "need 1 to 256 classes, got " << classes.size();
  for (const std::string& name : classes) {
    STEREODET_CHECK(!name.empty() && name.find_first_of(" \t\n,") == std::string::npos)
        << "class names must be non-empty, without spaces or commas, got '" << name << "'";
  }
}

nlohmann::json NewModelJson(const std::string& architecture) {
  nlohmann::json j;
  j["version"] = kModelConfigVersion;
  j["architecture"] = architecture;
  return j;
}

std::string FinishModelJson(nlohmann::json j, const WeightsRecord& weights,
                            const std::optional<StereoOptions>& stereo) {
  if (!weights.fnv1a64.empty()) {
    j["weights"] = {{"file", kModelWeightsFile},
                    {"fnv1a64", weights.fnv1a64},
                    {"input_channels", weights.input_channels},
                    {"parameters", weights.parameters}};
    if (!weights.training_run.empty()) j["weights"]["training_run"] = weights.training_run;
  }
  if (stereo) j["stereo"] = nlohmann::json::parse(StereoSettingsJson(*stereo));
  return j.dump(2) + "\n";
}

nlohmann::json ParseModelJson(const std::string& text, const std::string& source,
                              const std::string& architecture) {
  nlohmann::json j = ParseJsonText(text, source);
  std::string field;
  try {
    field = "version";
    const int version = JsonInt(j, field, source);
    if (version != kModelConfigVersion) {
      throw ParseError(source, 0, field, "unsupported version " + std::to_string(version));
    }
    field = "architecture";
    if (j.at(field).get<std::string>() != architecture) {
      throw ParseError(
          source, 0, field,
          "expected \"" + architecture + "\" (a model of `train " + architecture + "`)");
    }
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, field, e.what());
  }
  return j;
}

}  // namespace internal

WeightsRecord ReadWeightsRecord(const std::string& text, const std::string& source) {
  WeightsRecord record;
  const nlohmann::json j = ParseJsonText(text, source);
  try {
    if (!j.is_object() || !j.contains("weights")) return record;
    const nlohmann::json& w = j.at("weights");
    record.fnv1a64 = w.at("fnv1a64").get<std::string>();
    record.input_channels = internal::JsonInt(w, "input_channels", source);
    if (!w.at("parameters").is_number_integer()) {
      throw ParseError(source, 0, "weights.parameters", "expected an integer");
    }
    record.parameters = w.at("parameters").get<int64_t>();
    if (w.contains("training_run")) record.training_run = w.at("training_run").get<std::string>();
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, "weights", e.what());
  }
  return record;
}

StereoOptions ReadStereoRecord(const std::string& text, const std::string& source) {
  const nlohmann::json j = ParseJsonText(text, source);
  if (!j.is_object() || !j.contains("stereo")) return StereoOptions();
  if (!j["stereo"].is_object()) throw ParseError(source, 0, "stereo", "expected an object");
  try {
    return StereoOptionsFromJson(j["stereo"].dump(), source);
  } catch (const std::invalid_argument& e) {
    // A value out of range (StereoOptions' checks; found by the model_json fuzzer: a ground
    // min_inlier_fraction of 1.2). The checks' message names the setting; it starts with the
    // source, which ParseError adds again.
    std::string message = e.what();
    if (message.rfind(source + ": ", 0) == 0) message.erase(0, source.size() + 2);
    throw ParseError(source, 0, "stereo", message);
  }
}

}  // namespace stereodet
