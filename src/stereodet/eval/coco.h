// COCO-format bounding-box evaluation, equal to pycocotools' COCOeval with iouType 'bbox'.
//
//   const CocoGroundTruth gt = ReadCocoGroundTruth("instances_val2017.json");
//   const std::vector<CocoDetection> dets = ReadCocoDetections("detections.json", gt);
//   const CocoEvalResult result = EvaluateCoco(gt, dets, CocoEvalOptions());
//   std::cout << FormatCocoSummary(result);  // the 12 lines of COCOeval.summarize()
//
// What "equal" means: the precision, recall and scores arrays and the 12 summary numbers are those
// of pycocotools 2.0 (cocodataset/cocoapi; PyPI's pycocotools, ppwwyyxx/cocoapi, computes the
// same) to the last bit, with numpy's float64 arithmetic reproduced where it decides a value:
// the IoU thresholds are np.linspace's, precision is tp / (tp + fp + np.spacing(1)), and a summary
// number is np.mean's pairwise sum. pycocotools' quirks are reproduced, not fixed
// (docs/metrics.md, "COCO mode"):
//   - a ground truth's "ignore" field is overwritten by its "iscrowd" (COCOeval._prepare): only
//     crowds and boxes outside the area range are ignored (CocoEvalOptions::honor_ignore_flag
//     changes that);
//   - a detection matched to a ground truth whose id is 0 counts as unmatched (pycocotools stores
//     the matched id and tests it against 0), so such a ground truth can never be found;
//   - summary number 0 (AP@[.5:.95]) averages maxDets = 100 whatever max_dets holds, and AP50 /
//     AP75 look up IoU thresholds equal to 0.5 / 0.75 exactly: -1 when there is none.
// Where pycocotools fails, this code decides: an empty results list evaluates (pycocotools'
// loadRes raises IndexError), a missing "iscrowd" reads as 0 (pycocotools raises KeyError), and a
// duplicated annotation id is refused (pycocotools silently evaluates one of the two twice).
// Segmentation and keypoint evaluation are not implemented.
#ifndef STEREODET_EVAL_COCO_H_
#define STEREODET_EVAL_COCO_H_

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/curves.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/score_metrics.h"

namespace stereodet {

// A COCO box: top-left corner and size, pixels. Width and height are not checked for sign, as
// pycocotools does not check them (a box of negative size overlaps nothing).
struct CocoBox {
  double x = 0, y = 0, width = 0, height = 0;
};

// One element of a COCO data set's "annotations".
struct CocoAnnotation {
  int64_t id = 0;
  int64_t image_id = 0;
  int64_t category_id = 0;
  CocoBox bbox;
  // The file's "area", px^2: for COCO the segment's area, not the box's. It decides the area
  // range, and so whether the annotation is ignored there.
  double area = 0;
  bool iscrowd = false;  // "iscrowd" nonzero; absent: false
  bool ignore = false;   // "ignore" nonzero; absent: false (see honor_ignore_flag)
};

struct CocoCategory {
  int64_t id = 0;
  std::string name;  // "" when the file has none
};

// A COCO ground-truth file (instances_*.json), as far as bbox evaluation reads it.
struct CocoGroundTruth {
  std::string source;                       // the file it was read from, for messages
  std::vector<int64_t> image_ids;           // "images"[*].id, sorted, each once
  std::vector<CocoCategory> categories;     // by id, each id once (the last of a repeated id)
  std::vector<CocoAnnotation> annotations;  // in file order
};

// One element of a COCO results file (the list COCO.loadRes reads).
struct CocoDetection {
  int64_t image_id = 0;
  int64_t category_id = 0;
  CocoBox bbox;
  double score = 0;
};

// Parses a ground-truth file's text; `source` names it in messages. Requires "images" and
// "categories" arrays (of objects with an integer "id"); "annotations" may be absent. Throws
// ParseError naming the source and the field ("annotations[12].bbox: expected 4 numbers") for
// text that is not JSON, a missing or mistyped field, or an annotation id given twice.
CocoGroundTruth ParseCocoGroundTruth(std::string_view text, const std::string& source);

// ReadFile + ParseCocoGroundTruth. Throws std::runtime_error if the file cannot be read.
CocoGroundTruth ReadCocoGroundTruth(const std::filesystem::path& path);

// Parses a results file's text: a JSON array of {"image_id", "category_id", "bbox": [x, y, w, h],
// "score"} objects (other fields are ignored), returned in file order. As pycocotools' loadRes,
// refuses a detection on an image that `gt` does not have: ParseError naming the element and the
// image id. Throws ParseError for text that is not JSON, a missing or mistyped field or a score
// that is not finite.
std::vector<CocoDetection> ParseCocoDetections(std::string_view text, const std::string& source,
                                               const CocoGroundTruth& gt);

// Reads and parses a results file as ParseCocoDetections does, in blocks: simdjson parses each
// block's whole elements as soon as they are read, so neither the file nor simdjson's index of it
// is held whole (on a COCO-sized file that halved the reading's CPU, docs/BENCHMARKS.md). A file
// the fast path refuses is read whole by the reader that names the error. With `fnv1a64`, the
// file's FNV-1a 64 hash continues from *fnv1a64 (Fnv1a64(bytes, *fnv1a64)). Throws
// std::runtime_error if the file cannot be read, ParseError as ParseCocoDetections.
std::vector<CocoDetection> ReadCocoDetections(const std::filesystem::path& path,
                                              const CocoGroundTruth& gt,
                                              uint64_t* fnv1a64 = nullptr);

// An object area range: an annotation is inside when min_area <= area <= max_area.
struct CocoAreaRange {
  std::string label;    // how the summary finds it: "all", "small", "medium", "large"
  double min_area = 0;  // px^2
  double max_area = 0;  // px^2
};

// pycocotools' defaults (Params.setDetParams).
// np.linspace(.5, .95, 10): 0.5 + i * ((0.95 - 0.5) / 9), the last exactly 0.95; the 9th is
// 0.8999999999999999, as numpy computes it.
std::vector<double> CocoIouThresholds();
// np.linspace(0, 1, 101): i * 0.01, the last exactly 1.
std::vector<double> CocoRecallThresholds();
// all [0, 1e10], small [0, 32^2], medium [32^2, 96^2], large [96^2, 1e10].
std::vector<CocoAreaRange> CocoAreaRanges();

// How COCO mode associates detections with ground truths.
enum class CocoMatcher {
  kCoco,     // pycocotools' greedy matching, quirks included (the default: equal to COCOeval)
  kOptimal,  // the paper's: the most true positives at every score threshold (coco_internal.h)
};
const char* CocoMatcherName(CocoMatcher matcher);  // "coco", "optimal"
// Also reads "greedy" as kCoco.
std::optional<CocoMatcher> ParseCocoMatcher(std::string_view text);

struct CocoEvalOptions {
  // kOptimal: per image, category, area range and IoU threshold, the association of the most TPs
  // at every score threshold, then the fewest FPs; a detection is excused (neither TP nor FP) by an
  // ignored ground truth or crowd it overlaps with IoU >= the threshold (any number of them) or by
  // lying outside the area range. Its precision, recall and summary are then read as pycocotools
  // reads its own (101 recall points, max_dets, area ranges). pycocotools' ground-truth-id-0 quirk
  // is not reproduced there.
  CocoMatcher matcher = CocoMatcher::kCoco;
  // T IoU thresholds; a detection matches a box when IoU >= threshold (a threshold of 1 acts as
  // 1 - 1e-10, as in pycocotools). Each in [0, 1].
  std::vector<double> iou_thresholds = CocoIouThresholds();
  // R recall points of the interpolated precision, increasing, each in [0, 1].
  std::vector<double> recall_thresholds = CocoRecallThresholds();
  // M limits on the detections kept per image and category (the highest scores), strictly
  // increasing, each >= 1. Three of them: the summary's AR lines name max_dets[0..2].
  std::vector<int> max_dets = {1, 10, 100};
  // A area ranges, labels distinct and non-empty, min_area <= max_area.
  std::vector<CocoAreaRange> area_ranges = CocoAreaRanges();
  // false (pycocotools): a ground truth is ignored when it is a crowd or outside the area range;
  // its "ignore" field is not read. true: also when its "ignore" is set (COCO's documented intent).
  bool honor_ignore_flag = false;
  // false (pycocotools): each area range is matched on its own, the ground truths outside it
  // ignored, so a detection may find another ground truth there than in range "all" (a range can
  // hold a TP that "all" does not). true (the paper's stable filter, `--coco-area-ranges stable`):
  // every range is counted from the one matching of range "all": a pair is a TP of the range of
  // its ground truth (and drops out of the others), a detection matched to nothing is a FP of the
  // ranges its own area is in, a ground truth in the range that nothing matched a FN; so no range
  // holds a TP, FP or FN that "all" does not. Needs the coco matcher and an area range "all".
  bool stable_area_ranges = false;
  // The operating-point metrics (CocoEvalResult::cells and score_stats): off by default, as
  // pycocotools has none. With the optimal matcher they cost one more association per image,
  // category, area range and IoU threshold.
  bool score_metrics = false;
  // The operating point of the cells: the detections with score >= this (of the max_dets.back()
  // kept per image and category) are associated; the arrays and stats always use every detection.
  double score_threshold = -std::numeric_limits<double>::infinity();
  // How scores become the probabilities of the Brier scores and calibration (as in KITTI mode:
  // with kNone and a score outside [0, 1] they are left out, CocoEvalResult::probability_metrics).
  ScoreTransform score_transform = ScoreTransform::kNone;
  int calibration_bins = 10;  // reliability bins over [0, 1], >= 1
  int num_threads = 0;        // threads over categories (0 = all); the result does not depend on it

  // Throws std::invalid_argument naming the field for a setting outside the ranges above.
  void Check() const;
};

// The number of summary numbers of COCOeval.summarize() for bbox.
inline constexpr int kNumCocoStats = 12;

// The number of operating-point summary numbers (CocoEvalResult::score_stats).
inline constexpr int kNumCocoScoreStats = 12;

// One IoU threshold x category x area range at the operating point (CocoEvalOptions::
// score_threshold), with max_dets.back() detections per image: the association of the matcher
// (pycocotools' greedy one restricted to the detections at or above the threshold; the optimal
// matcher's of the most TPs, then fewest FPs, then largest total IoU) counted as docs/metrics.md
// defines it for KITTI mode: a valid ground truth is a TP or a FN, a detection a TP, a FP or
// neither (ignored as the arrays ignore it).
struct CocoCell {
  int64_t num_valid_gt = 0;  // ground truths not ignored in the area range
  OperatingPoint at_threshold;
  // Over labels: one term per valid ground truth; over detections: per TP or FP; over all: both.
  // NaN means as in KITTI mode (no term, or scores that are not probabilities).
  BrierScores brier;
  CalibrationResult calibration;  // over the TP and FP detections
};

// COCOeval.accumulate()'s arrays and summarize()'s numbers. The arrays are row-major in the order
// of their names, as numpy holds them: precision[t][r][k][a][m] is at
// (((t * R + r) * K + k) * A + a) * M + m, where t indexes options.iou_thresholds, r
// options.recall_thresholds, k category_ids, a options.area_ranges and m options.max_dets.
struct CocoEvalResult {
  CocoEvalOptions options;                  // as evaluated
  std::vector<int64_t> image_ids;           // the I images evaluated, sorted
  std::vector<int64_t> category_ids;        // the K categories, sorted
  std::vector<std::string> category_names;  // of category_ids, in their order
  // T x R x K x A x M: the interpolated precision (the precision envelope at the first detection
  // reaching recall r; 0 beyond the highest recall), in [0, 1]. -1 where the category has no
  // ground truth that is not ignored in the area range.
  std::vector<double> precision;
  // T x K x A x M: the recall with all max_dets[m] detections, -1 as above.
  std::vector<double> recall;
  // T x R x K x A x M: the score of the detection each precision entry was read at, 0 beyond the
  // highest recall, -1 as above.
  std::vector<double> scores;
  // summarize()'s numbers in its order: AP@[.5:.95], AP50, AP75, AP small, medium, large (at
  // maxDets max_dets[2], except the first at 100), AR@max_dets[0], [1], [2], AR small, medium,
  // large (at max_dets[2]). Each the mean of its array entries that are not -1; -1 when there is
  // none.
  std::array<double, kNumCocoStats> stats{};
  // Per category (category_ids' order), the same 12 numbers over that category alone: what
  // COCOeval prints with params.catIds = [that id] (detectron2's per-category AP is [k][0]).
  std::vector<std::array<double, kNumCocoStats>> category_stats;

  // With options.score_metrics: T x K x A cells, (t * K + k) * A + a (CellIndex); else empty.
  std::vector<CocoCell> cells;
  // False when a score is outside [0, 1] and options.score_transform is kNone: the cells' Brier
  // scores and calibration are NaN and score_stats -1.
  bool probability_metrics = true;
  // With options.score_metrics, in FormatCocoSummary's order: the Brier score over labels at IoU
  // [.50:.95], .50, .75; the same three over detections, over all, and of the ECE. Each the mean of
  // the cells' values (area "all") over the categories and the thresholds named, leaving out the
  // NaN ones; -1 when none is left (or without score_metrics).
  std::array<double, kNumCocoScoreStats> score_stats{};

  int64_t num_gt = 0;          // ground truths evaluated (on an evaluated image and category)
  int64_t num_gt_skipped = 0;  // ground truths of an image or category the file does not list
  int64_t num_detections = 0;  // detections evaluated (before max_dets)
  int64_t num_detections_skipped = 0;  // of a category the ground truth does not have
  double seconds = 0;                  // EvaluateCoco's time, s

  size_t PrecisionIndex(int t, int r, int k, int a, int m) const;
  size_t RecallIndex(int t, int k, int a, int m) const;
  size_t CellIndex(int t, int k, int a) const;
};

// COCOeval(gt, loadRes(dets), 'bbox'): evaluate(), accumulate(), summarize(). Every image and
// category of `gt` is evaluated; detections of a category `gt` does not list are left out
// (counted in num_detections_skipped), as are ground truths of unlisted images or categories.
// Requires: every detection's image_id is one of gt.image_ids (ParseCocoDetections ensures it;
// std::invalid_argument otherwise), options.Check().
CocoEvalResult EvaluateCoco(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                            const CocoEvalOptions& options);

// The summary as COCOeval.summarize() prints it, 12 lines:
//  " Average Precision  (AP) @[ IoU=0.50:0.95 | area=   all | maxDets=100 ] = 0.370",
// then, with options.score_metrics, 12 more in the same layout:
//  " Brier over labels  (BL) @[ IoU=0.50:0.95 | area=   all | maxDets=100 ] = 0.512".
std::string FormatCocoSummary(const CocoEvalResult& result);

// Each category's AP, AP50, AP75, APs, APm, APl and AR@max_dets[2] as a table, one line per
// category in category_ids' order (-1 printed as "-"):
//   "category         id     AP   AP50   AP75    APs    APm    APl  AR100"
std::string FormatCocoCategories(const CocoEvalResult& result);

// The names of score_stats: BL, BL50, BL75, BD, BD50, BD75, BA, BA50, BA75, ECE, ECE50, ECE75.
const std::array<const char*, kNumCocoScoreStats>& CocoScoreStatNames();

}  // namespace stereodet

#endif  // STEREODET_EVAL_COCO_H_
