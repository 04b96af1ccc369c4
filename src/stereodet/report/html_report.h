// The evaluation report: figures of one or several results folders (results.json of `stereodet
// eval --out`) as SVG and PNG files, and report/index.html, one self-contained page (inline SVG,
// inline CSS, the plotted numbers as JSON; nothing is fetched when it is opened). `stereodet
// report DIR...` is WriteReport; `stereodet eval --out DIR --report` writes DIR/report/ the same
// way (EvaluationOptions::report). See docs/report.md.
//
//   ReportOptions options;
//   options.results = {"eval-rgb", "eval-rgbh"};  // one colour per folder
//   options.out = "report-rgb-vs-rgbh";
//   const ReportResult report = WriteReport(options);  // report.index: .../index.html
#ifndef STEREODET_REPORT_HTML_REPORT_H_
#define STEREODET_REPORT_HTML_REPORT_H_

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stereodet/report/frame_view.h"
#include "stereodet/report/svg_plot.h"

namespace stereodet {

// What a results folder holds: `eval --out` (results.json), `eval sweep --out` (sweep.csv),
// `eval compare --out` (compare.csv) or `eval --coco-gt --coco-det --out` (results.json with
// "mode": "coco"; its figures and tables are coco_report.h's).
enum class ReportKind { kEval, kSweep, kCompare, kCoco };

// One results folder and the name its series carry in legends and tables.
struct ReportSource {
  std::string label;
  ReportKind kind = ReportKind::kEval;
  // kCoco: results.json with LoadCocoReportData's additions (coco_report.h).
  // kEval: results.json as written by WriteEvalReport, with each cell's exact curve read from the
  // CSV its "curve_csv" names into "curve" (an object of columns: threshold, tp, fp, fn,
  // precision, recall, fp_per_frame and, with AOS, orientation; null for an empty field).
  nlohmann::json results;
  // kSweep, kCompare: the CSV's rows, each column as a number (NaN for "-" or empty), the text
  // columns (class, metric, difficulty, filter) as text.
  struct Row {
    std::map<std::string, double> number;
    std::map<std::string, std::string> text;
  };
  std::vector<Row> rows;
  // kCompare with `--bootstrap`: bootstrap.csv's rows, then bootstrap_breakdown.csv's (those have
  // the text column "axis" and the numbers lower, upper); empty without them.
  std::vector<Row> paired;
  std::filesystem::path folder;  // where it was read from (shown in the page; may be empty)
  // kCompare: the last path components of the two detection folders compare.json names (A, B),
  // for the legends; empty when the folder has no compare.json (written before it existed).
  std::string name_a, name_b;
  // kEval: the per-detection records (matches.csv of `eval --records`, MatchRecordsFile) where
  // the folder has them, for the worst frames' views; empty otherwise.
  std::filesystem::path records;
};

// A results folder's label in a report: its last path component, trailing separators and `.`
// ignored ("runs/eval/" and "runs/eval/." give "eval").
std::string FolderLabel(const std::filesystem::path& folder);

// Reads FOLDER/results.json (and the curve CSVs it names), or else FOLDER/sweep.csv, or else
// FOLDER/compare.csv. Throws std::runtime_error naming the folder if it holds none of them, or the
// file if it is not one of stereodet's (results.json without a "results" array, a CSV without its
// columns).
ReportSource ReadReportSource(const std::filesystem::path& folder, const std::string& label);

// The figures of `sources`, per evaluated cell (class x metric x difficulty x overlap set) of the
// first source, each source's series overlaid (one colour per source with several):
//   pr_CELL           precision vs recall: the exact curve (curves/pr_CELL.csv) and, for the
//                     KITTI matcher, the devkit's 41 slots ("kitti.precision" at recall i/40);
//                     AP_R40 / AP_R11 in the legend
//   roc_CELL          recall vs false positives per frame (the same curve points)
//   reliability_CELL  fraction of TPs vs mean score per calibration bin (bins with detections), the
//                     diagonal, the ECE in the legend
//   localization_CELL median 3D centre error and median |depth error| per distance bin (m);
//                     whiskers up to the 90th percentile; only where a bin has a TP with 3D boxes
//   breakdown_AXIS_CELL  AP_R40 per bin of each `--breakdown` axis (LET cells: APL_R40 beside it;
//                     --bootstrap: whiskers; --breakdown-naive: the naive bins' bars)
//   errors_CELL       with `eval --errors`: the AP_R40 points fixing each error type gains (TIDE's
//                     cls, loc, both, dupe, bkg, missed; then every FP, every FN)
// and per class x metric x overlap set:
//   brier_CLASS_METRIC  the Brier scores over labels, detections and all, side by side per
//   difficulty
// CELL is class_metric_difficulty in lower case, with _OVERLAPS when the first source has several
// overlap sets (the curve CSV names of WriteEvalReport).
// For `eval sweep` folders, per cell: sweep_CELL, precision and recall of the naive and the stable
// filter against the filter value. For `eval compare` folders, per cell: compare_CELL, the mean
// |depth error| of A and of B, their difference B - A and the stereo model dz = z^2 / (b f) dd
// against the bin centre (m).
// Requires: at least one source, all of one kind (throws std::invalid_argument).
struct ReportFigure {
  std::string section;  // the page's heading it goes under: "Car 2d" ("Car 2d, loose overlaps")
  Plot plot;
};
std::vector<ReportFigure> ReportFigures(const std::vector<ReportSource>& sources);

// The page: a header per source (folder, tool, matcher, frames, input hash, command line), a
// summary table (per source and cell: labels, detections, AP_R40, AP_R11, AOS_R40, best F1,
// Brier over labels / detections / all, ECE), then the figures by section, each
// as inline SVG in a <figure class="stereodet-figure" id="fig-ID"> with its caption and links to
// figures/ID.svg and figures/ID.png (when `with_png`); a <script type="application/json"
// id="stereodet-figures"> with every PlotToJson; and a few lines of script that log the number of
// figures to the console (the browser test's control).
// With `views`, a section "Worst frames" (<table id="worst-frames">): per results folder and class,
// the frames with most FNs and most FPs, their counts, and links (<a class="stereodet-view-link">)
// to their image and bird's-eye views under the report folder.
struct ReportFrameViews {
  std::string label;         // the results folder's label
  std::string folder;        // the views' folder under the report: "views" or "views/N"
  bool has_records = false;  // false: the folder has no matches.csv (no views; the page says why)
  FrameViewsResult views;
};
std::string ReportHtml(const std::vector<ReportSource>& sources,
                       const std::vector<ReportFigure>& figures, bool with_png,
                       const std::vector<ReportFrameViews>& views = {});

struct ReportOptions {
  // Results folders, all of one kind: each holds results.json, sweep.csv or compare.csv.
  std::vector<std::filesystem::path> results;
  std::vector<std::string> labels;  // one per folder for legends; empty: the folders' names
  // The report folder (one run per folder, a StagedFolder: a folder that report did not make is
  // refused). Empty: with one results folder RESULTS/report, with several required.
  std::filesystem::path out;
  bool png = true;  // also figures/*.png (skipped with a note where PngFromSvgAvailable() is false)
  double png_scale = 2.0;  // PNG pixels per SVG px
  int worst_frames = 3;    // views of this many worst frames per class and kind (0: none)
  void Check() const;      // throws std::invalid_argument
};

struct ReportResult {
  std::filesystem::path index;               // OUT/index.html
  std::vector<std::filesystem::path> files;  // every file written, under OUT
  int num_figures = 0;
  int num_views = 0;               // frame views written (each an image and a bird's-eye view)
  bool png = false;                // PNG files were written
  std::vector<std::string> notes;  // e.g. why PNG files are missing
};

// Writes index.html and figures/ID.svg (and .png) for `sources` into `dir` (created; files written
// atomically), and for every eval source with records the views of its worst frames (`worst`
// with most FNs and as many with most FPs per class, first metric, moderate;
// WriteWorstFrameViews) into dir/views/ (dir/views/N/ for source N with several). WriteReport and
// RunEvaluation's report call this.
ReportResult WriteReportFiles(const std::filesystem::path& dir,
                              const std::vector<ReportSource>& sources, bool png, double png_scale,
                              int worst_frames = ReportOptions().worst_frames);

// `stereodet report`: reads the folders and writes the report folder, replacing it whole.
ReportResult WriteReport(const ReportOptions& options);

}  // namespace stereodet

#endif  // STEREODET_REPORT_HTML_REPORT_H_
