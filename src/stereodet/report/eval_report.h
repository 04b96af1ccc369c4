// Writing evaluation results: results.json (every number, the options, the tool version, and per
// cell the name of its curve CSV: "curve_csv", "roc_csv", "curve_points"), one CSV per curve (the
// exact curve, lossless), the filter-sweep CSV and the KITTI-like text table. Every file is written
// atomically (temp file + rename).
#ifndef STEREODET_REPORT_EVAL_REPORT_H_
#define STEREODET_REPORT_EVAL_REPORT_H_

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/compare.h"
#include "stereodet/eval/error_analysis.h"
#include "stereodet/eval/evaluator.h"

namespace stereodet {

// What the tool read, for the record.
struct EvalRunInfo {
  std::string tool_version;
  std::string gt_path, det_path, split_path;
  std::vector<std::string> frames_without_detections;  // ids whose detection file was missing
  std::string command_line;
  // What was read, as 16 hex digits (empty if not computed): EvalInput::input_hash.
  std::string input_hash;
  bool lenient = false;
  std::optional<double> score_if_missing;  // EvalInputOptions::score_if_missing (`--score`)
  std::vector<std::string> ignored_files;  // EvalInput::ignored_files
  std::vector<std::string> skipped_lines;  // EvalInput::skipped_lines ("FILE:LINE: field F: ...")
  std::string det_run;                     // EvalInput::det_run (empty: no DET/run.json)
  std::vector<std::string> det_not_from_run;  // EvalInput::det_not_from_run
  // `eval --calibration FILE`: the file, and the detections whose scores it replaced (empty, 0:
  // none).
  std::string calibration_path;
  int64_t calibrated_detections = 0;
};

// One evaluation of the same frames under one set of options, e.g. one overlap set of
// `--overlaps strict,loose`. Its results are tagged with DescribeOverlaps(options.classes).
struct EvalRun {
  EvalOptions options;
  EvalResult result;
  // With `eval --bootstrap N`: the intervals of the same frames and options (Bootstrap), in
  // results.json (top-level "bootstrap", and each cell's) and after the run's table.
  std::optional<BootstrapResult> bootstrap = std::nullopt;
  // With `eval --errors`: the TIDE-style analysis of every cell (AnalyzeAllErrors, EvalResult's
  // order), in results.json (each cell's "errors"), OUT/errors.csv and after the run's table.
  std::optional<std::vector<ErrorAnalysis>> errors = std::nullopt;
};

// Notes for the reader, one line each: scores that are not probabilities (Brier and ECE left out)
// or transformed, and cells with kSmallSampleLabels valid labels or fewer (marked '*' in the
// table; the KITTI matcher's AP_R40 cap). In the table's footer and results.json "notes".
std::vector<std::string> EvalNotes(const std::vector<EvalRun>& runs);

// The whole result as JSON. NaN (not computed) becomes null. With several runs, "results" holds
// every run's entries, each tagged "overlaps"; "options" are the first run's, with the overlap sets
// of all runs in "overlaps" and their thresholds in "overlap_sets".
nlohmann::json EvalResultToJson(const std::vector<EvalRun>& runs, const EvalRunInfo& info);
nlohmann::json EvalResultToJson(const EvalResult& result, const EvalOptions& options,
                                const EvalRunInfo& info);

// Writes OUT/results.json, OUT/summary.csv and per evaluated class x metric x difficulty
// OUT/curves/pr_CLASS_METRIC_DIFFICULTY.csv (PrCsv), roc_*.csv (RocCsv, the detector ROC),
// reliability_*.csv and localization_*.csv; with a filter also pr_naive_*.csv and pr_stable_*.csv
// (the curves under the filter in each mode). With several runs every curve file name ends in
// _OVERLAPS (pr_car_bev_moderate_loose.csv) and summary.csv has one row per run and cell (its
// last column, overlaps, says which). Returns the paths written.
std::vector<std::filesystem::path> WriteEvalReport(const std::filesystem::path& out_dir,
                                                   const std::vector<EvalRun>& runs,
                                                   const EvalRunInfo& info);
std::vector<std::filesystem::path> WriteEvalReport(const std::filesystem::path& out_dir,
                                                   const EvalResult& result,
                                                   const EvalOptions& options,
                                                   const EvalRunInfo& info);

// The per-detection records of every cell (ClassResult::records, EvalOptions::keep_records) as CSV,
// streamed to `path` atomically; `frames` are those the result was evaluated on. One row per
// record, cells in result order, then the records' order. Columns:
//   frame (id), class, metric, difficulty, min_overlap, outcome (tp, fp, fn, ignored, dontcare),
//   detection, label (indices in file order, -1 for none), score (the detection's, full precision),
//   iou (MatchRecord::iou), then the filter attributes of each side, empty where the side is
//   absent: det_type, det_height_px, det_width_px, det_distance_m, label_type, label_height_px,
//   label_width_px, label_distance_m (the 3D location's z), label_occluded, label_truncated,
//   label_difficulty (the easiest difficulty the label meets: Easy, Moderate, Hard, or empty),
//   label_valid (MatchRecord::label_valid, 1 or 0).
// Sizes are 2D box heights and widths to 6 significant digits; score and iou at full precision.
// Returns the number of rows.
int64_t WriteMatchRecordsCsv(const std::filesystem::path& path, const EvalResult& result,
                             const std::vector<EvalFrame>& frames);

// A PR curve as CSV: threshold, tp, fp, fn, precision, recall, fp_per_frame, and with AOS the
// orientation ratio (similarity / (tp + fp)); one row per curve point, descending threshold.
std::string PrCsv(const std::vector<CurvePoint>& curve, int64_t num_frames, bool with_aos);
// The detector ROC as CSV: fp_per_frame (ascending), recall, threshold, tp, fp; one row per curve
// point.
std::string RocCsv(const std::vector<CurvePoint>& curve, int64_t num_frames);

// A table like KITTI's: per class and metric, rows AP_R40 / AP_R11 (and AOS) for Easy, Moderate,
// Hard, then the operating-point counts and best F1 at Moderate (or the first difficulty
// evaluated); the valid label count per cell (marked '*' at kSmallSampleLabels or fewer with the
// KITTI matcher), the Brier score over labels and the ECE. One block per run, then EvalNotes.
std::string FormatEvalTable(const std::vector<EvalRun>& runs);
std::string FormatEvalTable(const EvalResult& result, const EvalOptions& options);

// The filter sweep as CSV: class, metric, difficulty, filter, value, then tp/fp/fn/precision/recall
// for the naive and the stable filter.
std::string FormatSweepCsv(const std::vector<SweepRow>& rows, FilterBound bound);

// `stereodet eval compare` as CSV: class, metric, difficulty, lower_m, upper_m, count_a,
// abs_dz_mean_a, count_b, abs_dz_mean_b, difference_b_minus_a, centre_error_mean_a,
// centre_error_mean_b, model_dz, difference_a_minus_b (metres, the shortest text that reads back
// exactly, as the other CSVs; an empty cell where a bin has no pair).
std::string FormatCompareCsv(const std::vector<CompareRow>& rows);

// `stereodet eval compare` as text: per class x metric x difficulty an empty line, a title and a
// header, then one line per distance bin: depth range, count and mean |depth error| (m) of A and
// of B, B - A, and the stereo model's depth error.
std::string FormatCompareTable(const std::vector<CompareRow>& rows);

// "12.3457" (4 decimals) or "nan"/"-" for NaN.
std::string FormatNumber(double value, int decimals = 4);

}  // namespace stereodet

#endif  // STEREODET_REPORT_EVAL_REPORT_H_
