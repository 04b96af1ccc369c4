// TIDE-style error analysis of one evaluation cell (class x overlap kind x difficulty): every false
// positive detection and every missed label gets one error type, and for each type the AP gained
// by fixing only that type (an "oracle"), recomputed with the cell's own matcher and AP.
//
// After TIDE (Bolya et al., "TIDE: A General Toolbox for Identifying Object Detection Errors",
// ECCV 2020; github dbolya/tide v1.0.1, tidecv/quantify.py and tidecv/errors/main_errors.py),
// adapted to KITTI's classes, neighbour classes, DontCare regions, difficulties and per-class
// overlap thresholds. docs/metrics.md, "Error analysis (TIDE)", has the same definitions with a
// worked example.
//
//   ErrorAnalysis a = AnalyzeErrors(frames, options, KittiClassSpec("Car"), OverlapKind::k3D,
//                                   Difficulty::kModerate);
//   a.delta_ap_r40[static_cast<int>(ErrorType::kLoc)]  // AP_R40 points gained by fixing Loc
//
// Definitions, for one overlap kind K and difficulty D. The analysed classes are
// EvalOptions::classes; t_f(C) = ClassSpec::min_overlap[K] of class C, t_b =
// ErrorAnalysisOptions::background_overlap. ov(d, l) is the overlap the matcher decides on
// (MatchOverlap; with the KITTI matcher in 2D / BEV / 3D, the devkit's own value where it can
// decide otherwise, as the matcher uses it). "Matchable at t" is ov > t for the KITTI matcher
// (the devkit's rule) and ov >= t for the optimal and VOC matchers.
//
//  1. The association: Evaluate's, at score threshold -inf, i.e. with every detection present
//     (TIDE classifies every detection; EvalOptions::score_threshold is not used). It gives each
//     detection of class C: TP, FP, ignored or DontCare; and each label of C or a neighbour of C:
//     "used" (a TP's label, or an ignored label: a neighbour class, a label failing D, or one
//     excused by an ignored detection) or "unused" (a valid label counted as a FN).
//  2. Every FP detection d of class C (only FPs: TP, ignored and DontCare-excused detections get no
//     type) gets the first type that holds, in TIDE's order of tests:
//       Loc:  the largest ov(d, l) over labels l of C or its neighbours (any difficulty) is
//             >= t_b and not matchable at t_f(C); its label is that l (first in file order among
//             equal overlaps).
//       Cls:  the largest ov(d, l) over labels of other classes (not C, not a neighbour of C, not
//             DontCare) is matchable at t_f of the label's class when that class is analysed,
//             else at t_f(C); its label is that l.
//       Dupe: the largest ov(d, l) over *used* labels of C or its neighbours is matchable at
//             t_f(C) (its label was taken by another detection, of any score; or it is an ignored
//             label, which in the KITTI matcher absorbs one detection only).
//       Bkg:  the largest ov(d, l) over all labels but DontCare is <= t_b.
//       Both: anything else (TIDE's "Other"); its overlap is then in (t_b, t_f) with a label of
//             another class and < t_b with the class's own labels.
//  3. Fix winners (TIDE's BestGTMatch): a label that is unused in its class and the target of
//     Loc errors (of that class's detections) or Cls errors (of other classes' detections) is
//     "explained"; of those errors the one of highest score (first in file order on ties) is its
//     winner (ClassifiedError::fixable), whatever its type.
//  4. Missed: an unused valid label of C (a FN at score -inf) that no Loc or Cls error explains.
//     Missed <= FN; the other FNs are explained.
//  5. Fixes (FixErrors), applied to copies of the frames:
//       Loc:  the winner's box (2D box and 3D box; score, type and alpha kept) is set to its
//             label's box; every other Loc detection is removed.
//       Cls:  the winner is relabelled to its label's class (so a Pedestrian detection on a Car
//             label becomes a Car detection: fixing Cls can add TPs to the Car cell); every
//             other Cls detection is removed. Either way C's own Cls detections leave the cell
//             of C.
//       Dupe, Bkg, Both: the detections are removed.
//       Missed: the labels are removed.
//     dAP(type) = AP(cell of C on the frames with that type fixed) - AP(cell as is), both with
//     Evaluate, the same matcher and AP (AP_R40 and AP_R11, percent). Special errors: FP = every FP
//     detection of C removed; FN = every FN label of C removed.
//
// Differences from TIDE, every one forced by KITTI's rules or by exact recomputation:
//  - TIDE matches like COCO: detections in descending score, each to its best unused label. Here
//    the association is the chosen matcher's (KITTI devkit: labels in file order, each taking the
//    unassigned detection of largest overlap; optimal: maximum TPs, then largest overlap sum). So
//    the duplicate of a label is not always the lower-scoring detection: both matchers keep the
//    better-overlapping one at score -inf, and they also associate crowded labels differently
//    (what is a Dupe under one matcher can be a TP under the other).
//  - TIDE turns a fixed error into a TP data point without matching again; here the fixed frames
//    are evaluated anew, so the fix's effect over the whole curve (the KITTI matcher's pass 1
//    thresholds, the optimal matcher's association at every score) is exact. In particular dAP
//    is not forced >= 0 (TIDE clamps its main errors at 0): removing a Dupe that scores above its
//    label's TP lowers the AP where that detection was the label's TP at higher thresholds.
//  - KITTI's excused detections (DontCare regions, ignored labels, detections lower than D's
//    minimum height) are not errors; TIDE classifies detections in crowd regions too.
//  - Neighbour classes (Van for Car) and labels failing D are the class's own, ignored labels:
//    a Car detection on a Van is not a Cls error, and one near a Van is a Loc error whose fix
//    removes it. TIDE has no such classes.
//  - TIDE has one positive threshold; KITTI's is per class (Car 0.7, Pedestrian 0.5): Cls is
//    tested at the label's class's threshold, the one that decides a TP once relabelled.
//  - Matchable is the matcher's own test: with the KITTI matcher an overlap exactly t_f is not a
//    match and counts as Loc (TIDE: Loc up to and including its threshold in every case).
//
// Cost: one Evaluate of all analysed classes (with per-detection records) for the
// classification, the overlaps of each FP detection with the frame's labels, and one Evaluate of
// the cell per error type with errors (at most 8). See docs/metrics.md for a measured figure.
#ifndef STEREODET_EVAL_ERROR_ANALYSIS_H_
#define STEREODET_EVAL_ERROR_ANALYSIS_H_

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/frame_data.h"

namespace stereodet {

struct ErrorAnalysisOptions {
  // t_b: below (or at) this overlap with every label a FP is a background error (TIDE's 0.1).
  double background_overlap = 0.1;

  // Throws std::invalid_argument unless 0 < background_overlap < 1. (AnalyzeErrors also requires
  // it below every analysed class's threshold of the kind.)
  void Check() const;
};

// TIDE's order (its tables and plots). The numeric values index the arrays of ErrorAnalysis.
enum class ErrorType : int8_t { kCls = 0, kLoc = 1, kBoth = 2, kDupe = 3, kBkg = 4, kMissed = 5 };
inline constexpr int kNumErrorTypes = 6;
// "cls", "loc", "both", "dupe", "bkg", "missed" (TIDE's short names, lower case; its "Miss").
const char* ErrorTypeName(ErrorType type);
std::optional<ErrorType> ParseErrorType(std::string_view text);

// TIDE's special errors.
enum class SpecialError {
  kFalsePositives,  // every FP detection of the class removed
  kFalseNegatives,  // every FN label of the class removed
};

// One false positive detection or one missed label.
struct ClassifiedError {
  int32_t frame = -1;      // index into the frames
  int32_t detection = -1;  // index into the frame's detections (file order); -1 for kMissed
  // Loc, Cls, Dupe: the label that decided (see the header comment); Both: the label of largest
  // overlap; Missed: the label itself; Bkg: -1. Index into the frame's labels (file order).
  int32_t label = -1;
  // Index into ErrorClassification::classes: the detection's class (kMissed: the label's).
  int32_t class_index = -1;
  // kCls: the class index of the label's type, -1 where that class is not analysed.
  int32_t target_class = -1;
  ErrorType type = ErrorType::kBkg;
  double score = std::numeric_limits<double>::quiet_NaN();  // the detection's; NaN for kMissed
  // The overlap that decided: with `label` (Loc, Cls, Dupe, Both); the largest with any label
  // (Bkg); 0 for kMissed. In the cell's overlap kind.
  double overlap = 0.0;
  // Loc and Cls: this detection is its label's winner (the label is unused and this is the
  // highest-scoring Loc or Cls error on it), so the fix makes it a TP of the label; other Loc and
  // Cls errors are removed by their fix. Always false for the other types.
  bool fixable = false;
};

// A valid label that no detection matched at score -inf (a FN).
struct UnmatchedLabel {
  int32_t frame = -1;
  int32_t label = -1;        // index into the frame's labels
  int32_t class_index = -1;  // into ErrorClassification::classes
  bool missed = false;       // true: a kMissed error; false: explained by a Loc or Cls error
};

// The classification of one overlap kind and difficulty, for every analysed class.
struct ErrorClassification {
  std::vector<ClassSpec> classes;  // the analysed classes, EvalOptions::classes' order
  OverlapKind kind = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  Matcher matcher = Matcher::kKitti;
  double background_overlap = 0.1;
  size_t num_frames = 0;
  // By frame, then the FP detections of every analysed class in file order, then the missed
  // labels in file order.
  std::vector<ClassifiedError> errors;
  // Every FN at score -inf, by frame, then label file order.
  std::vector<UnmatchedLabel> false_negatives;
  // Evaluate's cell of each class (classes' order) at score threshold -inf, without records and
  // AOS: ap_r40 / ap_r11 are the cells' AP as is, at_threshold the TP / FP / FN the types split.
  // Every cell is computed (require_detections is not applied here).
  std::vector<ClassResult> cells;

  // The errors of `class_index`'s detections (and missed labels) of each type.
  std::array<int64_t, kNumErrorTypes> Count(int class_index) const;
  // The analysed class named `name` (case-insensitive), or -1.
  int ClassIndex(const std::string& name) const;
};

// Classifies every FP detection and FN label of every class in options.classes for `kind` and
// `difficulty` (options.metrics and options.difficulties are not consulted; filters, breakdowns
// and score_threshold are ignored). Requires: options.Check() passes, ea.Check() passes, class
// names distinct (case-insensitive), compat kDevkit, and background_overlap below every class's
// min_overlap[kind]. Throws std::invalid_argument otherwise.
ErrorClassification ClassifyErrors(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                                   OverlapKind kind, Difficulty difficulty,
                                   const ErrorAnalysisOptions& ea = {});

// Copies of `frames` with the errors of `types` fixed for the class `class_index` (see the header
// comment, 5.): its own errors of those types, and, with kCls, the other classes' Cls winners on
// its labels relabelled to it. Other classes' errors are left alone. Labels and detections keep
// their order; removed ones are left out. Requires: `classification` made from these frames.
std::vector<EvalFrame> FixErrors(const std::vector<EvalFrame>& frames,
                                 const ErrorClassification& classification, int class_index,
                                 const std::vector<ErrorType>& types);
// The same for a special error of class `class_index`.
std::vector<EvalFrame> FixSpecialError(const std::vector<EvalFrame>& frames,
                                       const ErrorClassification& classification, int class_index,
                                       SpecialError special);

// One cell's analysis. AP and dAP in percent points, as ClassResult's.
struct ErrorAnalysis {
  std::string class_name;
  OverlapKind kind = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  Matcher matcher = Matcher::kKitti;
  double min_overlap = 0.5;         // t_f
  double background_overlap = 0.1;  // t_b
  // False where Evaluate would not evaluate the cell (EvalOptions::require_detections: no
  // detection of the class with a valid box of the kind); the APs and dAPs are NaN then, the
  // counts are filled.
  bool evaluated = true;

  int64_t num_valid_labels = 0;
  int64_t tp = 0, fp = 0, fn = 0;     // the association at score -inf (fp = sum of the 5 FP types)
  double ap_r40 = 0.0, ap_r11 = 0.0;  // the cell as is (equal to Evaluate's)

  // Detections of the class of each type (labels for kMissed), ErrorType's order.
  std::array<int64_t, kNumErrorTypes> count{};
  // Other classes' detections whose Cls fix makes them TPs of this class (counted in their own
  // class's kCls, not in `count`).
  int64_t cls_incoming = 0;
  // dAP: AP with only that type fixed minus `ap_*`. 0 exactly where nothing is to fix (the
  // evaluation is then skipped).
  std::array<double, kNumErrorTypes> delta_ap_r40{}, delta_ap_r11{};
  // The special errors: every FP removed, every FN removed.
  double delta_fp_r40 = 0.0, delta_fp_r11 = 0.0;
  double delta_fn_r40 = 0.0, delta_fn_r11 = 0.0;

  double seconds = 0.0;  // wall time of the cell's fixed evaluations
};

// The analysis of the cell (spec, kind, difficulty). The analysed classes are options.classes with
// the entry named as `spec` replaced by `spec` (appended if there is none): their detections are
// the other classes' of Cls. Requirements as ClassifyErrors. Cost: ClassifyErrors plus up to 8
// Evaluate calls of the one cell.
ErrorAnalysis AnalyzeErrors(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                            const ClassSpec& spec, OverlapKind kind, Difficulty difficulty,
                            const ErrorAnalysisOptions& ea = {});

// Every cell of `options` (class-major, then overlap kind, then difficulty, as EvalResult), one
// classification per kind and difficulty.
std::vector<ErrorAnalysis> AnalyzeAllErrors(const std::vector<EvalFrame>& frames,
                                            const EvalOptions& options,
                                            const ErrorAnalysisOptions& ea = {});

}  // namespace stereodet

#endif  // STEREODET_EVAL_ERROR_ANALYSIS_H_
