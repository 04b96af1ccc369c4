// Options and small shared types of the evaluation: which matcher, which overlap, which classes.
//
// Definitions of every metric and of each KITTI quirk kept in `--matcher kitti` are in
// docs/metrics.md; this header only names the knobs.
#ifndef STEREODET_EVAL_EVAL_OPTIONS_H_
#define STEREODET_EVAL_EVAL_OPTIONS_H_

#include <Eigen/Core>
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/filter.h"
#include "stereodet/kitti/object.h"
#include "stereodet/util/strings.h"  // EqualsIgnoreCase, for the class names

namespace stereodet {

// How detections are associated with labels.
enum class Matcher {
  kKitti,    // KITTI's official devkit (devkit_object, evaluate_object.cpp), quirks included
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

// Which overlap decides a match. The numeric values index ClassSpec::min_overlap. kLetBev and
// kLet3D are LET-3D-AP's longitudinal-error-tolerant BEV and 3D overlaps (let.h, docs/metrics.md
// "LET-3D-AP"): the detection moved along its line of sight to the label, a match also needing a
// longitudinal affinity above 0; their TP-weighted AP is LET-APL (ClassResult::apl_r40).
enum class OverlapKind { k2D = 0, kBev = 1, k3D = 2, kLetBev = 3, kLet3D = 4 };
inline constexpr int kNumOverlapKinds = 5;
const char* OverlapKindName(OverlapKind kind);  // "2d", "bev", "3d", "let-bev", "let-3d"
std::optional<OverlapKind> ParseOverlapKind(std::string_view text);
// True for kLetBev and kLet3D.
constexpr bool IsLetKind(OverlapKind kind) {
  return kind == OverlapKind::kLetBev || kind == OverlapKind::kLet3D;
}
// The plain overlap a kind measures the aligned box with: kBev for kLetBev, k3D for kLet3D, the
// kind itself otherwise (also the DontCare test of a LET kind: regions are not moved).
constexpr OverlapKind PlainKind(OverlapKind kind) {
  return kind == OverlapKind::kLetBev  ? OverlapKind::kBev
         : kind == OverlapKind::kLet3D ? OverlapKind::k3D
                                       : kind;
}

// The longitudinal error tolerance of the LET kinds (let.h; Waymo's defaults).
struct LetOptions {
  // The longitudinal tolerance of a label at range r (m, from the sensor to its centre):
  // max(longitudinal_tolerance_fraction * r, min_longitudinal_tolerance_m).
  double longitudinal_tolerance_fraction = 0.1;
  double min_longitudinal_tolerance_m = 0.5;
  // The sensor whose line of sight the tolerance runs along, in the rectified camera frame (m).
  // The default, the frame's origin, is KITTI's reference camera 0; the left colour camera 2 sits
  // about 6 cm to its left (calib P2: -P2(0,3) / P2(0,0) along x).
  Eigen::Vector3d sensor_m = Eigen::Vector3d::Zero();

  // Throws std::invalid_argument on a negative or non-finite fraction or minimum, both zero (no
  // tolerance at all: every affinity 0), or a non-finite sensor position.
  void Check() const;
};

// One evaluated class. Names compare case-insensitively, as in KITTI's devkit.
struct ClassSpec {
  std::string name;                     // "Car"
  std::vector<std::string> neighbours;  // labels of these classes are ignored, e.g. {"Van"}
  // Minimum overlap for a match, indexed by OverlapKind (2D, BEV, 3D, LET-BEV, LET-3D). Only the
  // evaluated kinds' need be in (0, 1].
  std::array<double, kNumOverlapKinds> min_overlap = {0.5, 0.5, 0.5, 0.5, 0.5};
};

// KITTI's settings for Car (neighbour Van, overlap 0.7), Pedestrian (Person_sitting, 0.5) and
// Cyclist (0.5). With `loose`, the BEV and 3D thresholds become 0.5 / 0.25 / 0.25 (KITTI's second
// set); 2D keeps 0.7 / 0.5 / 0.5. The LET kinds take their plain kind's threshold, so that LET
// changes only what is forgiven (the loose set is the nearest to Waymo's 0.5 / 0.3 / 0.3). Another
// name gets no neighbours and 0.5 everywhere.
ClassSpec KittiClassSpec(const std::string& name, bool loose = false);

// KITTI's two overlap sets (KittiClassSpec's thresholds), as OpenPCDet prints both.
enum class OverlapSet { kStrict, kLoose };
const char* OverlapSetName(OverlapSet set);  // "strict", "loose"
std::optional<OverlapSet> ParseOverlapSet(std::string_view text);
// "strict" or "loose" when every class has that set's KittiClassSpec thresholds (strict first, for
// classes where both agree), else "custom".
std::string DescribeOverlaps(const std::vector<ClassSpec>& classes);

// How scores are turned into probabilities for the Brier scores and calibration (only there: AP,
// curves and the operating point always use the raw scores, so they do not depend on it).
enum class ScoreTransform {
  kNone,     // scores are probabilities already
  kSigmoid,  // scores are logits: p = 1 / (1 + exp(-s))
};
const char* ScoreTransformName(ScoreTransform transform);  // "none", "sigmoid"
std::optional<ScoreTransform> ParseScoreTransform(std::string_view text);
double ApplyScoreTransform(ScoreTransform transform, double score);

// D-ECE, the detection ECE over joint bins of the score and the 2D box (Kuppers et al.,
// "Multivariate confidence calibration for object detection", CVPR-W 2020; netcal's
// ECE(detection=True)): the features score, box centre x / image width, centre y / image height,
// box width / image width, box height / image height, each split into equal-width bins over [0, 1]
// (a value of 1 in the last bin); a detection with a feature outside [0, 1] falls in no bin and
// takes no part.
struct DeceOptions {
  // Bins of the score, centre x, centre y, width and height, in that order.
  std::array<int, 5> bins = {5, 5, 5, 5, 5};
  // The image the 2D boxes are in, px (KITTI's left colour image: 1242 x 375).
  double image_width_px = 1242.0;
  double image_height_px = 375.0;

  // Throws std::invalid_argument on a bin count outside [1, 100], more than 10^6 bins in all, or a
  // non-positive or non-finite image size.
  void Check() const;
};

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
  // box of that kind (2D: left >= 0; BEV: x, z != -1000 and w, l > 0; 3D: x, y, z != -1000 and
  // h, w, l > 0). Kept in every matcher so the tables line up; a class that is not evaluated is
  // reported with evaluated = false.
  bool require_detections = true;

  // Brier scores and calibration need probabilities: with kNone and any detection's score outside
  // [0, 1] they are left out (NaN; EvalResult::probability_metrics false).
  ScoreTransform score_transform = ScoreTransform::kNone;

  // AOS is computed (2D only, as the devkit) unless a detection has alpha == -10 (devkit rule).
  bool compute_aos = true;

  // Reliability curve: equal-width score bins over [0, 1].
  int calibration_bins = 10;
  // D-ECE's bins (CalibrationResult::dece).
  DeceOptions dece;
  // Localization error of matched pairs, binned by the label's depth z (m).
  double distance_bin_m = 5.0;
  double max_distance_m = 80.0;

  // The longitudinal tolerance of the LET kinds (metrics kLetBev, kLet3D).
  LetOptions let;

  // Extra filter on labels and detections (difficulty filtering is always KITTI's).
  FilterOptions filter;

  // Breakdowns (breakdown.h): each cell's figures again per bin of each axis, from the cell's own
  // matching (ClassResult::breakdown). Empty: none.
  std::vector<BreakdownOptions> breakdowns;
  // Also each bin evaluated the naive way, for comparison (BreakdownBin::naive; `eval
  // --breakdown-naive`): labels and detections outside the bin struck (a detection without a value
  // on the axis kept, as it may be in the bin; DontCare regions stay), then matched on their own,
  // as a naive filter does. One more evaluation per bin and cell.
  bool breakdown_naive = false;

  // Keep every cell's per-detection records (ClassResult::records). Memory: 24 bytes a row, about
  // (detections + unmatched labels) x overlap kinds x difficulties rows.
  bool keep_records = false;

  int num_threads = 0;  // 0 = all hardware threads

  // Whether `metrics` holds a LET kind (kLetBev, kLet3D).
  bool HasLetKind() const;

  // Throws std::invalid_argument on an empty class list, a threshold outside (0, 1], bins < 1,
  // compat kOpenPcdet with another matcher than kKitti or with a LET kind, ...
  void Check() const;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_EVAL_OPTIONS_H_
