#include "stereodet/eval/eval_options.h"

#include <algorithm>
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
    case OverlapKind::kLetBev:
      return "let-bev";
    case OverlapKind::kLet3D:
      return "let-3d";
  }
  return "?";
}

std::optional<OverlapKind> ParseOverlapKind(std::string_view text) {
  for (OverlapKind k : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D, OverlapKind::kLetBev,
                        OverlapKind::kLet3D}) {
    if (EqualsIgnoreCase(text, OverlapKindName(k))) return k;
  }
  return std::nullopt;
}

ClassSpec KittiClassSpec(const std::string& name, bool loose) {
  ClassSpec spec;
  spec.name = name;
  // (2D, BEV and 3D); the LET kinds copy BEV and 3D.
  const auto set = [&](double image, double box) {
    spec.min_overlap = {image, box, box, box, box};
  };
  if (EqualsIgnoreCase(name, "Car")) {
    spec.neighbours = {"Van"};
    set(0.7, loose ? 0.5 : 0.7);
  } else if (EqualsIgnoreCase(name, "Pedestrian")) {
    spec.neighbours = {"Person_sitting"};
    set(0.5, loose ? 0.25 : 0.5);
  } else if (EqualsIgnoreCase(name, "Cyclist")) {
    set(0.5, loose ? 0.25 : 0.5);
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

void DeceOptions::Check() const {
  int64_t total = 1;
  for (const int b : bins) {
    STEREODET_CHECK(b >= 1 && b <= 100) << "D-ECE bins must be in [1, 100], got " << b;
    total *= b;
  }
  STEREODET_CHECK(total <= 1000000) << "D-ECE: " << total << " bins in all, at most 10^6";
  STEREODET_CHECK(std::isfinite(image_width_px) && image_width_px > 0 &&
                  std::isfinite(image_height_px) && image_height_px > 0)
      << "D-ECE: the image size must be positive, got " << image_width_px << " x "
      << image_height_px;
}

bool EvalOptions::HasLetKind() const {
  return std::any_of(metrics.begin(), metrics.end(), IsLetKind);
}

void EvalOptions::Check() const {
  STEREODET_CHECK(!classes.empty()) << "no class to evaluate";
  STEREODET_CHECK(!metrics.empty()) << "no overlap kind (2d, bev, 3d, let-bev, let-3d) to evaluate";
  STEREODET_CHECK(!difficulties.empty()) << "no difficulty to evaluate";
  for (const ClassSpec& c : classes) {
    STEREODET_CHECK(!c.name.empty()) << "empty class name";
    // The evaluated kinds' thresholds only: a spec made with three (2D, BEV, 3D) leaves the LET
    // kinds' at 0, which matters only when they are evaluated.
    for (OverlapKind kind : metrics) {
      const double tau = c.min_overlap[static_cast<int>(kind)];
      STEREODET_CHECK(tau > 0 && tau <= 1)
          << "class " << c.name << ": min overlap (" << OverlapKindName(kind)
          << ") must be in (0, 1], got " << tau;
    }
  }
  STEREODET_CHECK(compat == EvalCompat::kDevkit || matcher == Matcher::kKitti)
      << "compat " << EvalCompatName(compat)
      << " reproduces a KITTI evaluation: it needs matcher kitti, got " << MatcherName(matcher);
  const bool has_let = HasLetKind();
  STEREODET_CHECK(compat == EvalCompat::kDevkit || !has_let)
      << "compat " << EvalCompatName(compat)
      << " has no LET overlaps (let-bev, let-3d): evaluate them without it";
  if (has_let) let.Check();
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
  dece.Check();
  filter.Check();
  for (const BreakdownOptions& b : breakdowns) b.Check();
}

}  // namespace stereodet
