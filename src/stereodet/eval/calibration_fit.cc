#include "stereodet/eval/calibration_fit.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "stereodet/eval/evaluator.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

// log(1 + exp(z)) without overflow: -log(1 - sigmoid(z)).
double Softplus(double z) { return z > 0 ? z + std::log1p(std::exp(-z)) : std::log1p(std::exp(z)); }
double Sigmoid(double z) { return 1.0 / (1.0 + std::exp(-z)); }

// Negative log likelihood of sigmoid(z) against the target t in [0, 1]: -(t log p + (1 - t) log(1
// - p)) = t softplus(-z) + (1 - t) softplus(z).
double NegLogLikelihood(double z, double t) { return t * Softplus(-z) + (1 - t) * Softplus(z); }

void CheckPairs(const std::vector<double>& x, const std::vector<uint8_t>& targets) {
  STEREODET_CHECK(x.size() == targets.size() && !x.empty())
      << "calibration fit: " << x.size() << " scores and " << targets.size() << " targets";
  for (double v : x) STEREODET_CHECK(std::isfinite(v)) << "calibration fit: a non-finite score";
}

// The fitted slope must keep the scores' order.
void CheckSlope(double slope, const char* method) {
  STEREODET_CHECK(std::isfinite(slope) && slope > 0)
      << method << ": the fitted slope is " << slope
      << ": the scores rank false positives above true positives, and no order-keeping map "
         "calibrates them";
}

}  // namespace

EvalOptions CalibrationFitOptions::DefaultEval() {
  EvalOptions o;
  o.metrics = {OverlapKind::k2D};
  o.difficulties = {Difficulty::kModerate};
  o.matcher = Matcher::kOptimal;
  return o;
}

void CalibrationFitOptions::Check() const {
  STEREODET_CHECK(eval.metrics.size() == 1)
      << "calibration fit: one overlap kind (--metrics), got " << eval.metrics.size();
  STEREODET_CHECK(eval.difficulties.size() == 1)
      << "calibration fit: one difficulty (--difficulties), got " << eval.difficulties.size();
  eval.Check();
}

ScoreCalibrator FitTemperature(const std::vector<double>& x, const std::vector<uint8_t>& targets) {
  CheckPairs(x, targets);
  // d/da of the negative log likelihood of sigmoid(a x): sum (sigmoid(a x) - t) x, increasing in a
  // (the loss is convex). Its root, bracketed, by safeguarded Newton.
  auto derivative = [&](double a, double* second) {
    double g = 0, h = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      const double p = Sigmoid(a * x[i]);
      g += (p - targets[i]) * x[i];
      h += p * (1 - p) * x[i] * x[i];
    }
    if (second) *second = h;
    return g;
  };
  double lo = 0.0, hi = 1.0;
  CheckSlope(derivative(lo, nullptr) < 0 ? 1.0 : 0.0, "temperature");
  while (derivative(hi, nullptr) < 0) {
    lo = hi;
    hi *= 2;
    STEREODET_CHECK(hi < 1e9) << "temperature: no finite optimum (the scores separate the true "
                                 "positives from the false positives perfectly)";
  }
  double a = (lo + hi) / 2;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
    double h = 0;
    const double g = derivative(a, &h);
    if (g == 0) break;
    (g < 0 ? lo : hi) = a;
    const double newton = h > 0 ? a - g / h : -1;
    a = newton > lo && newton < hi ? newton : (lo + hi) / 2;
  }
  ScoreCalibrator c;
  c.method = CalibrationMethod::kTemperature;
  c.slope = a;
  c.intercept = 0.0;
  return c;
}

ScoreCalibrator FitPlatt(const std::vector<double>& x, const std::vector<uint8_t>& targets) {
  CheckPairs(x, targets);
  double positives = 0;
  for (uint8_t t : targets) positives += t;
  const double negatives = static_cast<double>(targets.size()) - positives;
  const double hi_target = (positives + 1) / (positives + 2), lo_target = 1 / (negatives + 2);
  std::vector<double> t(targets.size());
  for (size_t i = 0; i < t.size(); ++i) t[i] = targets[i] ? hi_target : lo_target;
  auto loss = [&](double a, double b) {
    double f = 0;
    for (size_t i = 0; i < x.size(); ++i) f += NegLogLikelihood(a * x[i] + b, t[i]);
    return f;
  };
  // Newton's method with a backtracking line search (Lin, Lin & Weng 2007, "A note on Platt's
  // probabilistic outputs"); scikit-learn's start: a = 0, b = log((N- + 1) / (N+ + 1)) in its
  // sign convention, here b = log((N+ + 1) / (N- + 1)).
  double a = 0.0, b = std::log((positives + 1) / (negatives + 1));
  double f = loss(a, b);
  for (int it = 0; it < 100; ++it) {
    double ga = 0, gb = 0, haa = 1e-12, hab = 0, hbb = 1e-12;
    for (size_t i = 0; i < x.size(); ++i) {
      const double p = Sigmoid(a * x[i] + b);
      const double w = p * (1 - p);
      ga += (p - t[i]) * x[i];
      gb += p - t[i];
      haa += w * x[i] * x[i];
      hab += w * x[i];
      hbb += w;
    }
    if (std::abs(ga) < 1e-12 * static_cast<double>(x.size()) &&
        std::abs(gb) < 1e-12 * static_cast<double>(x.size())) {
      break;
    }
    const double det = haa * hbb - hab * hab;
    const double da = -(hbb * ga - hab * gb) / det, db = -(haa * gb - hab * ga) / det;
    double step = 1.0;
    bool moved = false;
    for (; step > 1e-12; step /= 2) {
      const double fn = loss(a + step * da, b + step * db);
      if (fn < f + 1e-4 * step * (ga * da + gb * db)) {
        a += step * da;
        b += step * db;
        moved = fn < f;
        f = fn;
        break;
      }
    }
    if (!moved) break;
  }
  CheckSlope(a, "platt");
  ScoreCalibrator c;
  c.method = CalibrationMethod::kPlatt;
  c.slope = a;
  c.intercept = b;
  return c;
}

ScoreCalibrator FitIsotonic(const std::vector<double>& x, const std::vector<uint8_t>& targets) {
  CheckPairs(x, targets);
  std::vector<size_t> order(x.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t i, size_t j) {
    return x[i] != x[j] ? x[i] < x[j] : targets[i] < targets[j];
  });
  // Equal scores first become one point, their mean target weighted by their number.
  std::vector<double> ux, uy, uw;
  for (const size_t i : order) {
    if (!ux.empty() && ux.back() == x[i]) {
      uy.back() += targets[i];
      uw.back() += 1;
    } else {
      ux.push_back(x[i]);
      uy.push_back(targets[i]);
      uw.push_back(1);
    }
  }
  for (size_t k = 0; k < uy.size(); ++k) uy[k] /= uw[k];
  // Pool adjacent violators: blocks of (weight, mean, first point), merged while a block's mean
  // is above the next one's.
  struct Block {
    double weight, mean;
    size_t first;
  };
  std::vector<Block> blocks;
  for (size_t k = 0; k < ux.size(); ++k) {
    blocks.push_back({uw[k], uy[k], k});
    while (blocks.size() >= 2 && blocks[blocks.size() - 2].mean >= blocks.back().mean) {
      const Block last = blocks.back();
      blocks.pop_back();
      Block& prev = blocks.back();
      prev.mean = (prev.weight * prev.mean + last.weight * last.mean) / (prev.weight + last.weight);
      prev.weight += last.weight;
    }
  }
  std::vector<double> fitted(ux.size());
  for (size_t b = 0; b < blocks.size(); ++b) {
    const size_t end = b + 1 < blocks.size() ? blocks[b + 1].first : ux.size();
    for (size_t k = blocks[b].first; k < end; ++k) fitted[k] = blocks[b].mean;
  }
  // Only the points where the fit changes (the first and last of each constant run) are needed
  // for the linear interpolation, as scikit-learn keeps them.
  ScoreCalibrator c;
  c.method = CalibrationMethod::kIsotonic;
  for (size_t k = 0; k < ux.size(); ++k) {
    const bool keep =
        k == 0 || k + 1 == ux.size() || fitted[k - 1] != fitted[k] || fitted[k] != fitted[k + 1];
    if (!keep) continue;
    c.x.push_back(ux[k]);
    c.y.push_back(std::clamp(fitted[k], 0.0, 1.0));
  }
  return c;
}

CalibrationFit FitScoreCalibration(const std::vector<EvalFrame>& frames,
                                   const CalibrationFitOptions& options) {
  options.Check();
  EvalOptions eval = options.eval;
  eval.keep_records = true;
  eval.score_threshold = -std::numeric_limits<double>::infinity();
  eval.breakdowns.clear();
  eval.filter = FilterOptions();
  const EvalResult result = Evaluate(frames, eval);
  const OverlapKind kind = eval.metrics.front();
  const Difficulty difficulty = eval.difficulties.front();
  const bool logits = eval.score_transform == ScoreTransform::kSigmoid;

  CalibrationFit fit;
  fit.calibration.scores_are_logits = logits;
  std::string counts;
  for (const ClassSpec& spec : eval.classes) {
    // A class that cannot be fitted: an error, or with skip_unfittable a record of why.
    auto unfittable = [&](const std::string& why, const ClassCalibrationFit& c) {
      STEREODET_CHECK(options.skip_unfittable) << "calibrate: class " << spec.name << " " << why;
      fit.calibration.unfitted.emplace_back(spec.name, why);
      ClassCalibrationFit out = c;
      out.class_name = spec.name;
      out.fitted = false;
      fit.classes.push_back(out);
      counts += fmt::format("{}{}: {} TP, {} FP (not fitted)", counts.empty() ? "" : "; ",
                            spec.name, c.num_tp, c.num_fp);
    };
    const ClassResult* cell = result.Find(spec.name, kind, difficulty);
    if (cell == nullptr || !cell->evaluated) {
      unfittable(
          fmt::format("has no detection with a valid {} box to fit on", OverlapKindName(kind)), {});
      continue;
    }
    std::vector<double> scores;
    std::vector<uint8_t> targets;
    for (const MatchRecord& r : cell->records) {
      if (r.detection < 0 || (r.outcome != Outcome::kTp && r.outcome != Outcome::kFp)) continue;
      scores.push_back(*frames[r.frame].detections[r.detection].score);
      targets.push_back(r.outcome == Outcome::kTp ? 1 : 0);
    }
    ClassCalibrationFit c;
    c.class_name = spec.name;
    c.num_tp = std::count(targets.begin(), targets.end(), 1);
    c.num_fp = static_cast<int64_t>(targets.size()) - c.num_tp;
    if (c.num_tp == 0 || c.num_fp == 0) {
      unfittable(fmt::format("has {} true and {} false positives in {} at {}: a calibrator needs "
                             "both",
                             c.num_tp, c.num_fp, OverlapKindName(kind), DifficultyName(difficulty)),
                 c);
      continue;
    }
    // Temperature and Platt work on logits.
    std::vector<double> x = scores;
    if (options.method != CalibrationMethod::kIsotonic) {
      for (double& v : x) v = CalibrationLogit(v, logits);
    }
    ScoreCalibrator calibrator;
    try {
      calibrator = options.method == CalibrationMethod::kTemperature ? FitTemperature(x, targets)
                   : options.method == CalibrationMethod::kPlatt     ? FitPlatt(x, targets)
                                                                     : FitIsotonic(x, targets);
    } catch (const std::invalid_argument& e) {
      if (!options.skip_unfittable) {
        throw std::invalid_argument("calibrate: class " + spec.name + ": " + e.what());
      }
      unfittable(e.what(), c);  // e.g. Platt's slope <= 0: the scores rank FPs above TPs
      continue;
    }
    const double n = static_cast<double>(scores.size());
    for (size_t i = 0; i < scores.size(); ++i) {
      const double before =
          std::clamp(ApplyScoreTransform(eval.score_transform, scores[i]), 1e-12, 1.0 - 1e-12);
      const double after = std::clamp(calibrator.Apply(scores[i], logits), 1e-12, 1.0 - 1e-12);
      const double t = targets[i];
      c.brier_before += (before - t) * (before - t) / n;
      c.brier_after += (after - t) * (after - t) / n;
      c.nll_before -= (t * std::log(before) + (1 - t) * std::log(1 - before)) / n;
      c.nll_after -= (t * std::log(after) + (1 - t) * std::log(1 - after)) / n;
    }
    counts += fmt::format("{}{}: {} TP, {} FP", counts.empty() ? "" : "; ", spec.name, c.num_tp,
                          c.num_fp);
    fit.calibration.classes.emplace_back(spec.name, std::move(calibrator));
    fit.classes.push_back(c);
  }
  std::string thresholds;
  for (const ClassSpec& spec : eval.classes) {
    thresholds += fmt::format("{}{} {:g}", thresholds.empty() ? "" : ", ", spec.name,
                              spec.min_overlap[static_cast<int>(kind)]);
  }
  fit.calibration.fitted_on = {{"frames", std::to_string(frames.size())},
                               {"matcher", MatcherName(eval.matcher)},
                               {"metric", OverlapKindName(kind)},
                               {"difficulty", DifficultyName(difficulty)},
                               {"min_overlap", thresholds},
                               {"method", CalibrationMethodName(options.method)},
                               {"targets", counts}};
  return fit;
}

}  // namespace stereodet
