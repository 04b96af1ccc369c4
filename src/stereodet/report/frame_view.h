// Frame views: one frame's labels and detections drawn on its left image, coloured by what the
// evaluation counted each of them as in one cell (class x metric x difficulty) — TP, FP, FN,
// ignored — with score and IoU as text, and the bird's-eye view of the LiDAR (or stereo) points
// with the 3D boxes in the same colours. The colours come from the evaluator's per-detection
// records (MatchRecord, as `eval --records` writes them to matches.csv), so a view agrees with the
// evaluation exactly. Views are SVG (the image embedded as a data: URI, so one file is the whole
// view) and PNG rasterized from it by librsvg (raster.h), like the report's figures.
// `stereodet view RESULTS` is WriteFrameViews; the report links the worst frames' views
// (WriteWorstFrameViews). See docs/report.md.
//
//   FrameViewsOptions options;
//   options.results = "eval-rgb";        // eval --out eval-rgb --records
//   options.frames = {"000042"};         // or empty: the worst frames
//   const FrameViewsResult views = WriteFrameViews(options);  // eval-rgb/views/...
#ifndef STEREODET_REPORT_FRAME_VIEW_H_
#define STEREODET_REPORT_FRAME_VIEW_H_

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/util/progress.h"

namespace stereodet {

// The colours of the outcomes (Okabe-Ito): TP bluish green, FP vermillion, FN blue, ignored and
// DontCare-excused grey. Labels are drawn dashed, detections solid.
inline constexpr const char* kViewTpColour = "#009E73";
inline constexpr const char* kViewFpColour = "#D55E00";
inline constexpr const char* kViewFnColour = "#0072B2";
inline constexpr const char* kViewIgnoredColour = "#999999";

// One row of matches.csv (WriteMatchRecordsCsv), the columns a view needs.
struct ViewRecord {
  std::string frame_id;
  std::string class_name;
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  double min_overlap = 0.0;
  Outcome outcome = Outcome::kNone;
  int detection = -1;  // index into the frame's detection file (0-based), -1 for a label alone
  int label = -1;      // index into the frame's label file, -1 for a detection alone
  double score = 0.0;  // NaN for a label alone
  double iou = 0.0;
};

// Reads a records file of `stereodet eval --records`. Throws ParseError naming the line and column
// for a row that is not one of stereodet's, std::runtime_error when the file cannot be read.
std::vector<ViewRecord> ReadMatchRecordsCsv(const std::filesystem::path& path);

// The records file of results folder `folder` (results.json parsed as `results`): matches.csv, or
// that of the first overlap set (matches_OVERLAPS.csv); empty when there is none.
std::filesystem::path MatchRecordsFile(const std::filesystem::path& folder,
                                       const nlohmann::json& results);

// One cell of the evaluation: the records of one class x metric x difficulty.
struct ViewCell {
  std::string class_name = "Car";
  OverlapKind metric = OverlapKind::k2D;
  Difficulty difficulty = Difficulty::kModerate;
  bool operator==(const ViewCell&) const = default;
};
std::string ViewCellName(const ViewCell& cell);  // "car_2d_moderate", as the curve files
bool InCell(const ViewRecord& record, const ViewCell& cell);

// What one view draws.
struct FrameViewData {
  std::string frame_id;
  std::vector<Object> labels;       // the frame's label file, in file order
  std::vector<Object> detections;   // the frame's detection file, in file order
  std::vector<ViewRecord> records;  // the records of this frame in one cell
  ViewCell cell;
  std::filesystem::path image;       // the left image (PNG); empty or missing: a grey canvas
  std::optional<Calibration> calib;  // needed for the points; boxes are drawn without it
  std::vector<VeloPoint> points;     // velodyne frame (LiDAR, or stereo points)
};

struct FrameViewOptions {
  // The bird's-eye view: x (right) from -side_m to +side_m, z (forward) from 0 to forward_m, in
  // the rectified camera frame, at px_per_m SVG px per metre; points binned into cells of cell_m
  // (one dark square per cell with a point, so the file stays small for 100k-point scans).
  double bev_side_m = 30.0;
  double bev_forward_m = 60.0;
  double bev_px_per_m = 8.0;
  double bev_cell_m = 0.2;
  // Canvas size (px) when the frame has no readable image: KITTI's.
  int canvas_width_px = 1242;
  int canvas_height_px = 375;
  // The detections drawn (`view --min-score`, `--top-k`): those scoring at least min_score, and of
  // those the top_k highest (ties in record order; 0 = all). Labels are always drawn (a TP whose
  // detection is left out shows its label alone); the counts below the image stay the frame's.
  double min_score = -std::numeric_limits<double>::infinity();
  int top_k = 0;
  void Check() const;  // throws std::invalid_argument for a non-positive size or top_k < 0
};

// The two views as standalone SVG documents, and what they drew. In the image view every record
// of the cell is one <rect class="box OUTCOME det|label" data-index="I"> at the object's 2D box
// (px, left image, which is drawn at (0, 0) at its own size): a TP row draws its detection and its
// label, every other row its one side; stroke 3 px. Detections are labelled with the score and the
// IoU ("0.91 IoU 0.83"), FNs with "FN IoU 0.30"; a text that would overlap one drawn before it
// moves away from its box (up for detections, down for labels) until it is clear, so that no two
// overlap where the canvas leaves room. Below the image a line of counts. The BEV view draws each
// drawn object that has 3D fields as a <polygon class="box OUTCOME det|label"> (its footprint,
// BevCorners), the points as grey squares, range lines every 10 m, the camera at the bottom centre.
struct FrameView {
  std::string image_svg, bev_svg;
  int num_tp = 0, num_fp = 0, num_fn = 0, num_ignored = 0;  // records drawn, by outcome
  int num_image_boxes = 0;  // <rect> boxes in the image view (a TP counts twice)
  int num_bev_boxes = 0;    // <polygon> boxes in the BEV view
  int num_points = 0;       // points inside the BEV range
  bool has_image = false;   // the image was embedded
};
// Throws std::invalid_argument for a record whose index is outside the frame's files.
FrameView DrawFrameView(const FrameViewData& data, const FrameViewOptions& options = {});

// Frames of a cell by how many FNs (or FPs) they have, most first, ties by frame id; frames with
// none are left out; at most `count`.
struct FrameCounts {
  std::string frame_id;
  int tp = 0, fp = 0, fn = 0;
};
std::vector<FrameCounts> CountByFrame(const std::vector<ViewRecord>& records, const ViewCell& cell);
std::vector<FrameCounts> WorstFrames(const std::vector<ViewRecord>& records, const ViewCell& cell,
                                     Outcome by, int count);

// `stereodet view`: views of frames of a results folder written by `eval --out RESULTS --records`.
// The labels, detections and split are read again from the folders results.json names (relative
// paths are relative to the working directory, as they were given to eval); the images, calib
// and velodyne folders are those beside the label folder (KITTI layout).
struct FrameViewsOptions {
  std::filesystem::path results;  // the results folder (results.json and matches.csv)
  // The frames to draw; empty: the `worst` frames with most FNs and the `worst` with most FPs
  // of each cell.
  std::vector<std::string> frames;
  int worst = 3;
  // The cells: classes (empty: every class of results.json), metric ("" : the first of
  // results.json), difficulty.
  std::vector<std::string> classes;
  std::string metric;
  Difficulty difficulty = Difficulty::kModerate;
  // Point clouds (.bin, velodyne frame) instead of DATASET/velodyne: a folder of .bin files, or
  // the output folder of `stereodet stereo --encode points` (its velodyne/). A folder with no
  // .bin file there or in velodyne/ is refused (std::runtime_error naming it).
  std::filesystem::path points;
  // Where the views go: OUT/FRAME_CELL_image.svg and _bev.svg (and .png). Empty: RESULTS/views.
  // Files are written atomically; the folder is not cleared.
  std::filesystem::path out;
  bool png = true;         // also PNG (skipped with a note where the build has no librsvg)
  double png_scale = 1.0;  // PNG pixels per SVG px (1: the image's own resolution)
  FrameViewOptions view;
  // Progress over the frames drawn; silent by default (the CLI draws it on stderr).
  ProgressOptions progress = {.stream = nullptr};
  void Check() const;  // throws std::invalid_argument
};

struct WrittenFrameView {
  std::string frame_id;
  ViewCell cell;
  std::string reason;  // "most FN", "most FP" or "asked"
  int tp = 0, fp = 0, fn = 0;
  // File names under the output folder (png empty without PNG).
  std::string image_svg, image_png, bev_svg, bev_png;
};

struct FrameViewsResult {
  std::vector<WrittenFrameView> views;  // by cell, then reason, then rank
  std::vector<std::filesystem::path> files;
  std::vector<std::string> notes;  // e.g. a frame without image, PNG not written
};

// Throws std::runtime_error when the results folder has no records file (names the flag
// --records), a frame asked for is not in the evaluation, or the folders cannot be read.
FrameViewsResult WriteFrameViews(const FrameViewsOptions& options);

// The views of the worst frames (most FN, most FP: `worst` each) of every class of `results`
// (results.json as parsed) in `metric` (empty: the first) at `difficulty`, read from
// `records_csv`, into `out`; for the report. Returns no views, and a note, when the frames cannot
// be read again (the input folders moved).
FrameViewsResult WriteWorstFrameViews(const nlohmann::json& results,
                                      const std::filesystem::path& records_csv,
                                      const std::filesystem::path& out,
                                      const FrameViewsOptions& options);

}  // namespace stereodet

#endif  // STEREODET_REPORT_FRAME_VIEW_H_
