// Internal to the eval module (used by EvaluateCoco, BootstrapCoco and their tests): the pieces of
// COCO mode's evaluation the bootstrap reuses, and the optimal matcher on one image, category,
// area range and IoU threshold.
//
// The paper's matcher in COCO terms (docs/metrics.md, "COCO mode: the optimal matcher"):
//  - a ground truth is valid unless it is a crowd, outside the area range or (with
//    CocoEvalOptions::honor_ignore_flag) marked "ignore"; the others are ignored;
//  - TP: a pair (valid ground truth, detection) with IoU >= tau in a matching of the most pairs;
//  - a detection in no pair is excused (neither TP nor FP) when its own area is outside the range
//    (as in pycocotools) or when it overlaps an ignored ground truth with IoU >= tau (a crowd by
//    the intersection over the detection's area, as KITTI's DontCare): an ignored ground truth
//    excuses any number of detections;
//  - among the matchings with the most pairs, one leaving the fewest false positives.
// With the detections taken in descending score, TP(s) and FP(s) at every score threshold s are
// the ranks of the transversal matroids of (all detections) and (detections nothing excuses): one
// augmenting-path search per detection in each of two incremental matchings gives both, and each
// detection's own outcome (a TP, a FP, or neither) is the step its arrival makes. A detection that
// grows the first matching grows the second (submodularity), so no detection is both.
#ifndef STEREODET_EVAL_COCO_INTERNAL_H_
#define STEREODET_EVAL_COCO_INTERNAL_H_

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/bipartite_internal.h"
#include "stereodet/eval/coco.h"
#include "stereodet/eval/score_metrics_internal.h"

namespace stereodet {

// Per detection, what accumulate() counts: a match (TP), ignored (neither), or neither flag (FP).
inline constexpr uint8_t kCocoMatched = 1;
inline constexpr uint8_t kCocoIgnored = 2;

// One image and category in one area range.
struct CocoImageCell {
  int num_dets = 0;  // detections by descending score (ties in file order), at most max_dets
  int num_gts = 0;
  const double* iou = nullptr;           // num_dets x num_gts, detection-major (BoxIou's values)
  const uint8_t* gt_valid = nullptr;     // per ground truth: 1 valid, 0 ignored
  const uint8_t* det_outside = nullptr;  // per detection: 1 if its area is outside the range
};

// One image's Brier terms (transformed scores s) in one IoU threshold's cell of area range "all":
// over labels, sum of (1 - s)^2 or 1 per valid ground truth; over detections, sum of (s - y)^2 per
// TP or FP; the FPs' s^2 (over all adds them to the label terms).
struct CocoImageBrierTerms {
  int32_t image = 0;
  int32_t t = 0;
  double label_sum = 0, detection_sum = 0, fp_square_sum = 0;
  int32_t labels = 0, detections = 0, fps = 0;
};

// One category's detections over all images, as accumulate() concatenates them (image by image in
// image order, each image's by score), with what the matcher made of each.
struct CocoCategoryDetections {
  std::vector<double> score;
  std::vector<int32_t> rank;   // the detection's position in its image's score order
  std::vector<int32_t> image;  // the image's index (CocoEvalResult::image_ids)
  std::vector<uint8_t> flags;  // [detection][area range][threshold]: kCocoMatched, kCocoIgnored
  std::vector<int64_t> num_valid_gt;  // per area range: ground truths not ignored (npig)
  // Per image with a ground truth of the category, in image order: the image, and its valid
  // ground truths per area range (valid_count[entry * A + a]).
  std::vector<int32_t> valid_image;
  std::vector<int32_t> valid_count;
  // With CocoEvalOptions::score_metrics, per (threshold, area range), t * A + a: the operating
  // point's counts and Brier / calibration terms.
  std::vector<int64_t> cell_tp, cell_fp, cell_fn;
  std::vector<ScoreMetricsAccumulator> cell_terms;
  std::vector<int32_t> gt_tp_det;  // memory of the evaluator
  // With score_metrics, when handed over (EvaluateCocoKeepingDetections): each image's Brier terms
  // in the cells of area range "all", image by image, thresholds ascending (for the bootstrap).
  std::vector<CocoImageBrierTerms> brier_terms;
};

// ParseCocoDetections' second reader: nlohmann's SAX parser, which names the element and field of
// any error. ParseCocoDetections reads with simdjson first and comes here when that fails; tests
// compare the two.
std::vector<CocoDetection> ParseCocoDetectionsNamingErrors(std::string_view text,
                                                           const std::string& source,
                                                           const CocoGroundTruth& gt);

// Where the text of a results file splits into the elements of its top array: a byte scan that
// follows strings (with their escapes) and the nesting of brackets and braces, from just inside
// the top array's '['. ReadCocoDetections' fallback where its guess of the split fails.
struct CocoArrayScanner {
  static constexpr size_t kNoClose = static_cast<size_t>(-1);
  // Scans text[from, to) on from where the last scan stopped. Returns the offset of the bracket
  // that closes the top array, or kNoClose if not reached; *last_cut becomes the offset of the
  // last comma between two elements of the top array, where one is scanned.
  size_t Scan(const char* text, size_t from, size_t to, size_t* last_cut);

  int depth = 1;
  bool in_string = false;
  bool escaped = false;  // the string's last byte was an unescaped backslash
};

// ReadCocoDetections' block size, bytes: the buffer, and simdjson's index of it, stay in the
// cache of a core and are reused block after block.
inline constexpr size_t kCocoReadBlockBytes = size_t{1} << 20;

// ReadCocoDetections with a block size (tests use a few bytes, to cut every element);
// *streamed: whether the fast path read the file (false: the whole-file reader did).
std::vector<CocoDetection> ReadCocoDetectionsInBlocks(const std::filesystem::path& path,
                                                      const CocoGroundTruth& gt, size_t block_bytes,
                                                      uint64_t* fnv1a64, bool* streamed);

// EvaluateCoco, also handing over every category's detections (in category order).
CocoEvalResult EvaluateCocoKeepingDetections(const CocoGroundTruth& gt,
                                             const std::vector<CocoDetection>& dets,
                                             const CocoEvalOptions& options,
                                             std::vector<CocoCategoryDetections>* categories);

// accumulate()'s arithmetic for one category, area range, max_dets and IoU threshold: the flags
// and scores of the `nd` kept detections in score order (ignored ones included: they make points
// of the curve too) and npig > 0 in; the recall, and the R interpolated precisions and their
// scores, written at precision[r * stride] and score_at[r * stride]. The same numbers, bit for
// bit, as numpy's cumsum, division, envelope and searchsorted over every detection, computed at
// the true positives alone (coco.cc says why that is exact).
struct CocoCurveScratch {
  std::vector<uint8_t> flags;  // threshold-major: flags[t * nd + j]
  std::vector<double> scores;
  std::vector<double> tp_precision;
  std::vector<uint32_t> tp_at, fp_before;
};
void CocoAccumulateCurve(const uint8_t* flags, const double* scores, size_t nd, int64_t npig,
                         const std::vector<double>& recall_thresholds, CocoCurveScratch* scratch,
                         double* recall, double* precision, double* score_at, size_t stride);

// CocoAccumulateCurve at every IoU threshold of result->options: the detections `sequence` of
// `in` (indices into its arrays, in score order) in area range a, into result's recall, precision
// and scores at (t, k, a, m).
void CocoAccumulateCurves(const CocoCategoryDetections& in, const std::vector<uint32_t>& sequence,
                          int k, int a, int m, int64_t npig, CocoCurveScratch* scratch,
                          CocoEvalResult* result);

// summarize(): result->stats from result->precision and result->recall (options and categories
// set), each number numpy's mean of its slice's entries other than -1.
void SummarizeCoco(CocoEvalResult* result);
// result->category_stats: each category's 12 numbers, summarize() over that category alone.
void SummarizeCocoCategories(CocoEvalResult* result);

// score_stats' averaging, shared by the evaluation and its bootstrap: for each of `num_metrics`
// metrics and each of the three IoU lines (every threshold, then 0.5, then 0.75, each threshold
// taken where it equals the line's exactly), the mean over those thresholds t (outer loop) and
// the `num_categories` categories k (inner) of value(metric, t, k), leaving out the NaN ones;
// written to out[metric * 3 + line], `none` where no value is left.
template <typename Value>
void AverageScoreStats(const std::vector<double>& iou_thresholds, int num_categories,
                       int num_metrics, Value value, double none, double* out) {
  const std::array<std::optional<double>, 3> lines = {std::nullopt, 0.5, 0.75};
  const int T = static_cast<int>(iou_thresholds.size());
  for (int metric = 0; metric < num_metrics; ++metric) {
    for (int line = 0; line < 3; ++line) {
      double sum = 0;
      int64_t n = 0;
      for (int t = 0; t < T; ++t) {
        if (lines[line] && iou_thresholds[t] != *lines[line]) continue;
        for (int k = 0; k < num_categories; ++k) {
          const double v = value(metric, t, k);
          if (std::isnan(v)) continue;
          sum += v;
          ++n;
        }
      }
      out[metric * 3 + line] = n > 0 ? sum / static_cast<double>(n) : none;
    }
  }
}

// The (area range, max_dets) indices summarize() reads, AP lines' and AR lines' ((-1, -1) for a
// line whose area label or max_dets the options do not have).
struct CocoSummarySlice {
  bool ap = true;
  int area = -1, max_dets = -1;
};
std::vector<CocoSummarySlice> CocoSummarySlices(const CocoEvalOptions& options);

// Reusable memory for one thread; the results do not depend on what it held.
class CocoOptimalMatcher {
 public:
  // Each detection's flags at IoU threshold `tau` (a match needs IoU >= tau) as the detections
  // arrive in order: kCocoMatched if it raised the most TPs, 0 if it raised the fewest FPs, else
  // kCocoIgnored. `flags` gets num_dets values.
  void Outcomes(const CocoImageCell& cell, double tau, std::vector<uint8_t>* flags);

  // The association of the first `num_present` detections (those at or above the operating
  // point): the most TPs, then the fewest FPs, then the largest total IoU of the pairs.
  // det_gt[d]: the ground truth of detection d's pair, or -1; flags[d]: kCocoMatched for a TP, 0
  // for a FP, kCocoIgnored for an excused detection (num_dets values each; -1 and kCocoIgnored
  // beyond num_present).
  void Associate(const CocoImageCell& cell, double tau, int num_present,
                 std::vector<int32_t>* det_gt, std::vector<uint8_t>* flags);

 private:
  // The edges (valid ground truths with IoU >= tau) and which detections could be excused.
  void BuildGraph(const CocoImageCell& cell, double tau, int num_present);

  DetAdjacency adjacency_;
  std::vector<uint8_t> excusable_;
  IncrementalMatching all_, unexcusable_;
  std::vector<WeightedEdge> edges_;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_COCO_INTERNAL_H_
