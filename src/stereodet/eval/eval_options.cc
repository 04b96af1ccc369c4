#include "stereodet/eval/eval_options.h"

#include <cctype>
#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

const char* MatcherName(Matcher matcher) {
  switch (matcher) {
    case Matcher::kKitti:
      return "kitti";
    case Matcher::kOptimal:
      return "optimal";
    case Matcher::kVoc:
      return "voc";
  }
  return "?";
}

std::optional<Matcher> ParseMatcher(std::string_view text) {
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    if (text == MatcherName(m)) return m;
  }
  return std::nullopt;
}

const char* EvalCompatName(EvalCompat compat) {
  switch (compat) {
    case EvalCompat::kDevkit:
      return "devkit";
    case EvalCompat::kOpenPcdet:
      return "openpcdet";
  }
  return "?";
}

std::optional<EvalCompat> ParseEvalCompat(std::string_view text) {
  for (EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    if (EqualsIgnoreCase(text, EvalCompatName(c))) return c;
  }
  return std::nullopt;
}

const char* OverlapKindName(OverlapKind kind) {
  switch (kind) {
    case OverlapKind::k2D:
      return "2d";
    case OverlapKind::kBev:
      return "bev";
    case OverlapKind::k3D:
      return "3d";
  }
  return "?";
}

std::optional<OverlapKind> ParseOverlapKind(std::string_view text) {
  for (OverlapKind k : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
    if (EqualsIgnoreCase(text, OverlapKindName(k))) return k;
  }
  return std::nullopt;
}

ClassSpec KittiClassSpec(const std::string& name, bool loose) {
  ClassSpec spec;
  spec.name = name;
  if (EqualsIgnoreCase(name, "Car")) {
    spec.neighbours = {"Van"};
    spec.min_overlap =
        loose ? std::array<double, 3>{0.7, 0.5, 0.5} : std::array<double, 3>{0.7, 0.7, 0.7};
  } else if (EqualsIgnoreCase(name, "Pedestrian")) {
    spec.neighbours = {"Person_sitting"};
    spec.min_overlap =
        loose ? std::array<double, 3>{0.5, 0.25, 0.25} : std::array<double, 3>{0.5, 0.5, 0.5};
  } else if (EqualsIgnoreCase(name, "Cyclist")) {
    spec.min_overlap =
        loose ? std::array<double, 3>{0.5, 0.25, 0.25} : std::array<double, 3>{0.5, 0.5, 0.5};
  }
  return spec;
}

const char* OverlapSetName(OverlapSet set) {
  switch (set) {
    case OverlapSet::kStrict:
      return "strict";
    case OverlapSet::kLoose:
      return "loose";
  }
  return "?";
}

std::optional<OverlapSet> ParseOverlapSet(std::string_view text) {
  for (OverlapSet s : {OverlapSet::kStrict, OverlapSet::kLoose}) {
    if (EqualsIgnoreCase(text, OverlapSetName(s))) return s;
  }
  return std::nullopt;
}

std::string DescribeOverlaps(const std::vector<ClassSpec>& classes) {
  for (const bool loose : {false, true}) {
    bool all = true;
    for (const ClassSpec& c : classes) {
      all &= c.min_overlap == KittiClassSpec(c.name, loose).min_overlap;
    }
    if (all) return loose ? "loose" : "strict";
  }
  return "custom";
}

const char* ScoreTransformName(ScoreTransform transform) {
  switch (transform) {
    case ScoreTransform::kNone:
      return "none";
    case ScoreTransform::kSigmoid:
      return "sigmoid";
  }
  return "?";
}

std::optional<ScoreTransform> ParseScoreTransform(std::string_view text) {
  for (ScoreTransform t : {ScoreTransform::kNone, ScoreTransform::kSigmoid}) {
    if (EqualsIgnoreCase(text, ScoreTransformName(t))) return t;
  }
  return std::nullopt;
}

double ApplyScoreTransform(ScoreTransform transform, double score) {
  switch (transform) {
    case ScoreTransform::kNone:
      return score;
    case ScoreTransform::kSigmoid:
      return 1.0 / (1.0 + std::exp(-score));
  }
  return score;
}

void EvalOptions::Check() const {
  STEREODET_CHECK(!classes.empty()) << "no class to evaluate";
  STEREODET_CHECK(!metrics.empty()) << "no overlap kind (2d, bev, 3d) to evaluate";
  STEREODET_CHECK(!difficulties.empty()) << "no difficulty to evaluate";
  for (const ClassSpec& c : classes) {
    STEREODET_CHECK(!c.name.empty()) << "empty class name";
    for (double tau : c.min_overlap) {
      STEREODET_CHECK(tau > 0 && tau <= 1)
          << "class " << c.name << ": min overlap must be in (0, 1], got " << tau;
    }
  }
  STEREODET_CHECK(compat == EvalCompat::kDevkit || matcher == Matcher::kKitti)
      << "compat " << EvalCompatName(compat)
      << " reproduces a KITTI evaluation: it needs matcher kitti, got " << MatcherName(matcher);
  STEREODET_CHECK(!std::isnan(score_threshold)) << "score_threshold is NaN";
  STEREODET_CHECK(calibration_bins >= 1 && calibration_bins <= 10000)
      << "calibration_bins must be in [1, 10000], got " << calibration_bins;
  // inf passes a "> 0" check and gives one bin of everything, NaN passes none of them silently.
  STEREODET_CHECK(std::isfinite(distance_bin_m) && distance_bin_m > 0)
      << "distance_bin_m must be a finite number > 0, got " << distance_bin_m
      << " (--distance-bin)";
  STEREODET_CHECK(std::isfinite(max_distance_m) && max_distance_m > 0)
      << "max_distance_m must be a finite number > 0, got " << max_distance_m;
  STEREODET_CHECK_LE(max_distance_m / distance_bin_m, 100000) << " (localization bins)";
  STEREODET_CHECK_GE(num_threads, 0);
  filter.Check();
  for (const BreakdownOptions& b : breakdowns) b.Check();
}

}  // namespace stereodet
