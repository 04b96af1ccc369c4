#include "stereodet/kitti/score_calibration.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {
namespace {

using json = nlohmann::json;

constexpr const char* kFormat = "stereodet score calibration";
constexpr int kVersion = 1;
// Probabilities are clamped this far from 0 and 1 before their logit (CalibrationLogit).
constexpr double kLogitClamp = 1e-7;

double Sigmoid(double z) { return 1.0 / (1.0 + std::exp(-z)); }

}  // namespace

const char* CalibrationMethodName(CalibrationMethod method) {
  switch (method) {
    case CalibrationMethod::kTemperature:
      return "temperature";
    case CalibrationMethod::kPlatt:
      return "platt";
    case CalibrationMethod::kIsotonic:
      return "isotonic";
  }
  return "?";
}

std::optional<CalibrationMethod> ParseCalibrationMethod(std::string_view text) {
  for (CalibrationMethod m :
       {CalibrationMethod::kTemperature, CalibrationMethod::kPlatt, CalibrationMethod::kIsotonic}) {
    if (EqualsIgnoreCase(text, CalibrationMethodName(m))) return m;
  }
  return std::nullopt;
}

double CalibrationLogit(double score, bool scores_are_logits) {
  if (scores_are_logits) return score;
  const double s = std::clamp(score, kLogitClamp, 1.0 - kLogitClamp);
  return std::log(s / (1.0 - s));
}

double ScoreCalibrator::Apply(double score, bool scores_are_logits) const {
  if (method != CalibrationMethod::kIsotonic) {
    return Sigmoid(slope * CalibrationLogit(score, scores_are_logits) + intercept);
  }
  if (score <= x.front()) return y.front();
  if (score >= x.back()) return y.back();
  // The first point above the score; the score lies in [x[k - 1], x[k]).
  const size_t k = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), score) - x.begin());
  const double t = (score - x[k - 1]) / (x[k] - x[k - 1]);
  return y[k - 1] + t * (y[k] - y[k - 1]);
}

void ScoreCalibrator::Check() const {
  if (method != CalibrationMethod::kIsotonic) {
    STEREODET_CHECK(std::isfinite(slope) && slope > 0)
        << CalibrationMethodName(method) << ": the slope must be finite and > 0 (the map must "
        << "keep the scores' order), got " << slope;
    STEREODET_CHECK(std::isfinite(intercept))
        << CalibrationMethodName(method) << ": the intercept must be finite, got " << intercept;
    STEREODET_CHECK(method == CalibrationMethod::kPlatt || intercept == 0)
        << "temperature: the intercept must be 0, got " << intercept;
    return;
  }
  STEREODET_CHECK(!x.empty() && x.size() == y.size())
      << "isotonic: x and y must be non-empty and of one length, got " << x.size() << " and "
      << y.size();
  for (size_t i = 0; i < x.size(); ++i) {
    STEREODET_CHECK(std::isfinite(x[i])) << "isotonic: x[" << i << "] is not finite";
    STEREODET_CHECK(y[i] >= 0 && y[i] <= 1)
        << "isotonic: y[" << i << "] = " << y[i] << " is not a probability in [0, 1]";
    if (i == 0) continue;
    STEREODET_CHECK(x[i] > x[i - 1])
        << "isotonic: x must ascend, x[" << i << "] = " << x[i] << " after " << x[i - 1];
    STEREODET_CHECK(y[i] >= y[i - 1])
        << "isotonic: y must not decrease, y[" << i << "] = " << y[i] << " after " << y[i - 1];
  }
}

const ScoreCalibrator* ScoreCalibration::Find(std::string_view class_name) const {
  for (const auto& [name, calibrator] : classes) {
    if (EqualsIgnoreCase(name, class_name)) return &calibrator;
  }
  return nullptr;
}

int64_t ScoreCalibration::Apply(std::vector<Object>* detections) const {
  int64_t changed = 0;
  for (Object& d : *detections) {
    const ScoreCalibrator* c = Find(d.type);
    if (c == nullptr) continue;
    STEREODET_CHECK(d.score.has_value() && std::isfinite(*d.score))
        << "calibration: a " << d.type << " detection without a finite score";
    d.score = c->Apply(*d.score, scores_are_logits);
    ++changed;
  }
  return changed;
}

void ScoreCalibration::Check() const {
  STEREODET_CHECK(!classes.empty() || !unfitted.empty()) << "calibration: no class";
  for (size_t i = 0; i < unfitted.size(); ++i) {
    STEREODET_CHECK(!unfitted[i].first.empty()) << "calibration: unfitted[" << i << "] has no name";
    for (const auto& [name, calibrator] : classes) {
      STEREODET_CHECK(!EqualsIgnoreCase(unfitted[i].first, name))
          << "calibration: class '" << name << "' both fitted and unfitted";
    }
  }
  for (size_t i = 0; i < classes.size(); ++i) {
    STEREODET_CHECK(!classes[i].first.empty()) << "calibration: classes[" << i << "] has no name";
    for (size_t j = 0; j < i; ++j) {
      STEREODET_CHECK(!EqualsIgnoreCase(classes[i].first, classes[j].first))
          << "calibration: class '" << classes[i].first << "' twice";
    }
    try {
      classes[i].second.Check();
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument("calibration: class '" + classes[i].first + "': " + e.what());
    }
  }
}

std::string ScoreCalibrationToJson(const ScoreCalibration& calibration) {
  json classes = json::array();
  for (const auto& [name, c] : calibration.classes) {
    json e = {{"class", name}, {"method", CalibrationMethodName(c.method)}};
    if (c.method == CalibrationMethod::kIsotonic) {
      e["x"] = c.x;
      e["y"] = c.y;
    } else {
      e["slope"] = c.slope;
      e["intercept"] = c.intercept;
      if (c.method == CalibrationMethod::kTemperature) e["temperature"] = 1.0 / c.slope;
    }
    classes.push_back(std::move(e));
  }
  json fitted_on = json::object();
  for (const auto& [key, value] : calibration.fitted_on) fitted_on[key] = value;
  json j = {{"format", kFormat},
            {"version", kVersion},
            {"scores_are_logits", calibration.scores_are_logits},
            {"classes", classes},
            {"fitted_on", fitted_on}};
  if (!calibration.unfitted.empty()) {
    json unfitted = json::array();
    for (const auto& [name, reason] : calibration.unfitted) {
      unfitted.push_back({{"class", name}, {"reason", reason}});
    }
    j["unfitted"] = unfitted;
  }
  return j.dump(1) + "\n";
}

ScoreCalibration ParseScoreCalibration(std::string_view text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    throw std::invalid_argument(source + ": not JSON: " + e.what());
  }
  auto field = [&](const json& object, const char* key, const std::string& where) -> const json& {
    STEREODET_CHECK(object.is_object() && object.contains(key))
        << source << ": " << where << key << " is missing";
    return object[key];
  };
  STEREODET_CHECK(j.is_object() && j.value("format", std::string()) == kFormat)
      << source << ": not a stereodet score calibration (its \"format\" is not \"" << kFormat
      << "\")";
  STEREODET_CHECK(field(j, "version", "") == kVersion)
      << source << ": version " << j["version"].dump() << ", this stereodet reads version "
      << kVersion;
  ScoreCalibration out;
  const json& logits = field(j, "scores_are_logits", "");
  STEREODET_CHECK(logits.is_boolean()) << source << ": scores_are_logits must be true or false";
  out.scores_are_logits = logits.get<bool>();
  const json& classes = field(j, "classes", "");
  STEREODET_CHECK(classes.is_array()) << source << ": classes must be a list";
  for (size_t i = 0; i < classes.size(); ++i) {
    const std::string where = "classes[" + std::to_string(i) + "].";
    const json& e = classes[i];
    auto number = [&](const char* key) {
      const json& v = field(e, key, where);
      STEREODET_CHECK(v.is_number()) << source << ": " << where << key << " must be a number";
      return v.get<double>();
    };
    auto numbers = [&](const char* key) {
      const json& v = field(e, key, where);
      STEREODET_CHECK(v.is_array() &&
                      std::all_of(v.begin(), v.end(), [](const json& x) { return x.is_number(); }))
          << source << ": " << where << key << " must be a list of numbers";
      return v.get<std::vector<double>>();
    };
    const json& name = field(e, "class", where);
    STEREODET_CHECK(name.is_string()) << source << ": " << where << "class must be a name";
    const json& method_text = field(e, "method", where);
    const std::optional<CalibrationMethod> method =
        method_text.is_string() ? ParseCalibrationMethod(method_text.get<std::string>())
                                : std::nullopt;
    STEREODET_CHECK(method.has_value())
        << source << ": " << where << "method must be temperature, platt or isotonic, got "
        << method_text.dump();
    ScoreCalibrator c;
    c.method = *method;
    if (c.method == CalibrationMethod::kIsotonic) {
      c.x = numbers("x");
      c.y = numbers("y");
    } else {
      c.slope = number("slope");
      c.intercept = number("intercept");
    }
    out.classes.emplace_back(name.get<std::string>(), std::move(c));
  }
  if (j.contains("fitted_on") && j["fitted_on"].is_object()) {
    for (const auto& [key, value] : j["fitted_on"].items()) {
      out.fitted_on.emplace_back(key, value.is_string() ? value.get<std::string>() : value.dump());
    }
  }
  if (j.contains("unfitted")) {
    const json& unfitted = j["unfitted"];
    STEREODET_CHECK(unfitted.is_array()) << source << ": unfitted must be a list";
    for (size_t i = 0; i < unfitted.size(); ++i) {
      const std::string where = "unfitted[" + std::to_string(i) + "].";
      const json& name = field(unfitted[i], "class", where);
      const json& reason = field(unfitted[i], "reason", where);
      STEREODET_CHECK(name.is_string() && reason.is_string())
          << source << ": " << where << "class and reason must be text";
      out.unfitted.emplace_back(name.get<std::string>(), reason.get<std::string>());
    }
  }
  try {
    out.Check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return out;
}

ScoreCalibration ReadScoreCalibration(const std::filesystem::path& path) {
  return ParseScoreCalibration(ReadFile(path, 64 << 20, "calibration file"), path.string());
}

void WriteScoreCalibration(const std::filesystem::path& path, const ScoreCalibration& calibration) {
  calibration.Check();
  WriteFileAtomically(path, ScoreCalibrationToJson(calibration));
}

}  // namespace stereodet
