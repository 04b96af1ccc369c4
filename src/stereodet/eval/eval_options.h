// Options and small shared types of the evaluation: which matcher, which overlap, which classes.
//
// Definitions of every metric and of each KITTI quirk kept in `--matcher kitti` are in
// docs/metrics.md; this header only names the knobs.
#ifndef STEREODET_EVAL_EVAL_OPTIONS_H_
#define STEREODET_EVAL_EVAL_OPTIONS_H_

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/filter.h"
#include "stereodet/kitti/object.h"

namespace stereodet {

// How detections are associated with labels.
enum class Matcher {
  kKitti,    // KITTI's devkit (evaluate_object_3d_offline), quirks included
  kOptimal,  // maximum number of true positives, then maximum total IoU (the paper's metric)
  kVoc,      // PASCAL VOC: detections in descending score, each to its best-overlapping label
};
const char* MatcherName(Matcher matcher);  // "kitti", "optimal", "voc"
std::optional<Matcher> ParseMatcher(std::string_view text);

// Whose KITTI evaluation `--matcher kitti` reproduces where they differ (docs/metrics.md,
// "OpenPCDet / mmdetection3d compatibility").
enum class EvalCompat {
  kDevkit,     // KITTI's devkit (the leaderboard's numbers)
  kOpenPcdet,  // OpenPCDet's / mmdetection3d's kitti_object_eval_python (its printed numbers)
};
const char* EvalCompatName(EvalCompat compat);  // "devkit", "openpcdet"
std::optional<EvalCompat> ParseEvalCompat(std::string_view text);

// Which overlap decides a match. The numeric values index ClassSpec::min_overlap.
enum class OverlapKind { k2D = 0, kBev = 1, k3D = 2 };
inline constexpr int kNumOverlapKinds = 3;
const char* OverlapKindName(OverlapKind kind);  // "2d", "bev", "3d"
std::optional<OverlapKind> ParseOverlapKind(std::string_view text);

// One evaluated class. Names compare case-insensitively, as in KITTI's devkit.
struct ClassSpec {
  std::string name;                     // "Car"
  std::vector<std::string> neighbours;  // labels of these classes are ignored, e.g. {"Van"}
  // Minimum overlap for a match, indexed by OverlapKind (2D, BEV, 3D).
  std::array<double, kNumOverlapKinds> min_overlap = {0.5, 0.5, 0.5};
};

// KITTI's settings for Car (neighbour Van, overlap 0.7), Pedestrian (Person_sitting, 0.5) and Cyclist
// (0.5). With `loose`, the BEV and 3D thresholds become 0.5 / 0.25 / 0.25 (KITTI's second set);
// 2D keeps 0.7 / 0.5 / 0.5. Another name gets no neighbours and 0.5 everywhere.
ClassSpec KittiClassSpec(const std::string& name, bool loose = false);

// Case-insensitive ASCII comparison (strcasecmp).
bool EqualsIgnoreCase(std::string_view a, std::string_view b);

struct EvalOptions {
  std::vector<ClassSpec> classes = {KittiClassSpec("Car"), KittiClassSpec("Pedestrian"),
                                    KittiClassSpec("Cyclist")};
  std::vector<OverlapKind> metrics = {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D};
  std::vector<Difficulty> difficulties = {Difficulty::kEasy, Difficulty::kModerate,
                                          Difficulty::kHard};
  Matcher matcher = Matcher::kKitti;
  // With kOpenPcdet (KITTI matcher only): OpenPCDet's label rule, DontCare use, rotated-box
  // overlaps, AOS switch and envelope (openpcdet_compat.h); every class is evaluated
  // (require_detections is not consulted).
  EvalCompat compat = EvalCompat::kDevkit;

  // Operating point: detections with score >= this take part in the statistics at a threshold
  // (TP/FP/FN, precision, recall, F1), the Brier scores, calibration, localization error and the
  // filtered statistics. Curves and AP always use every detection.
  double score_threshold = -std::numeric_limits<double>::infinity();

  // KITTI's devkit evaluates a class (per overlap kind) only if some detection of it has a valid
  // box of that kind (2D: left >= 0; BEV: x != -1000; 3D: y != -1000). Kept in every matcher so the
  // tables line up; a class that is not evaluated is reported with evaluated = false.
  bool require_detections = true;

  // AOS is computed (2D only, as the devkit) unless a detection has alpha == -10 (devkit rule).
  bool compute_aos = true;

  // Reliability curve: equal-width score bins over [0, 1].
  int calibration_bins = 10;
  // Localization error of matched pairs, binned by the label's depth z (m).
  double distance_bin_m = 5.0;
  double max_distance_m = 80.0;

  // Extra filter on labels and detections (difficulty filtering is always KITTI's).
  FilterOptions filter;

  int num_threads = 0;  // 0 = all hardware threads

  // Throws std::invalid_argument on an empty class list, a threshold outside (0, 1], bins < 1,
  // compat kOpenPcdet with another matcher than kKitti, ...
  void Check() const;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_EVAL_OPTIONS_H_
