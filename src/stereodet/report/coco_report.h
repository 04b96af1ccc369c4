// The evaluation report of COCO-mode results folders (`stereodet eval --coco-gt --coco-det --out`):
// the figures and tables html_report.h puts in the page when its folders hold COCO results
// (results.json with "mode": "coco", precision.npy, and with --coco-brier reliability.csv).
#ifndef STEREODET_REPORT_COCO_REPORT_H_
#define STEREODET_REPORT_COCO_REPORT_H_

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stereodet/report/svg_plot.h"

namespace stereodet {

// Reads what the figures need from a COCO results folder into its parsed results.json:
//   "report_pr": {"recall": [R], "AP": [R], "AP50": [R], "AP75": [R]}: the precision at each
//       recall threshold, averaged over the categories with ground truth (summarize()'s mean of
//       the entries > -1; -1 where none), area "all", the largest max_dets; "AP" also over the
//       IoU thresholds (the mean of the 12 numbers' AP is the mean of this curve). From
//       precision.npy (float64, C order, shape T x R x K x A x M as results.json's "arrays" says).
//   "report_reliability" (when reliability.csv is there): per score bin at IoU 0.5, area "all",
//       pooled over the categories: {"lower", "upper", "count", "mean_score", "tp_fraction"}
//       arrays (count-weighted means; NaN for an empty bin).
// Throws std::runtime_error naming the file if precision.npy is missing, is not a float64 array of
// the shape results.json gives, or reliability.csv lacks its columns.
void LoadCocoReportData(const std::filesystem::path& folder, nlohmann::json* results);

// One folder's results and its name in legends.
struct CocoReportSource {
  std::string label;
  const nlohmann::json* results = nullptr;  // with LoadCocoReportData's additions
};

// The figures, each source's series overlaid (one colour per source), section by section:
//   "Precision-recall": coco_pr_50, coco_pr_75, coco_pr_mean (precision vs recall, the mean
//       over categories; AP50 / AP75 / AP in the legend)
//   "Summary": coco_stats, the 12 numbers as bars (with the bootstrap's intervals as whiskers
//       where the folder has them)
//   "Categories": coco_categories, AP per category (the first source's categories)
//   "Calibration" (where a source has reliability.csv): coco_reliability, fraction of TPs vs
//       mean score per bin at IoU 0.5, the diagonal, ECE50 in the legend
struct CocoReportFigure {
  std::string section;
  Plot plot;
};
std::vector<CocoReportFigure> CocoReportFigures(const std::vector<CocoReportSource>& sources);

// The page's summary: a table with a row per source and the 12 numbers (and BL, BD, BA, ECE at
// [.50:.95] with --coco-brier), each with its interval where the folder has a bootstrap; a second
// table of per-category AP, AP50, AP75 (first source's categories; one column group per source).
std::string CocoSummaryHtml(const std::vector<CocoReportSource>& sources);

// A source's line in the page's header: folder, tool, matcher, images, categories, ground truths,
// detections, input hash, command line.
std::string CocoHeaderHtml(const std::string& label, const std::filesystem::path& folder,
                           const nlohmann::json& results);

}  // namespace stereodet

#endif  // STEREODET_REPORT_COCO_REPORT_H_
