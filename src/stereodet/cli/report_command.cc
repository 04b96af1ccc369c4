// `stereodet report RESULTS_DIR... [--out DIR] [--labels A,B] [--no-png]`: figures (SVG, PNG) and
// one self-contained HTML page of one or several results folders (docs/report.md). The library call
// is WriteReport(ReportOptions) (report/html_report.h).
#include <fmt/format.h>

#include <memory>
#include <sstream>

#include "stereodet/cli/commands.h"
#include "stereodet/report/frame_view.h"
#include "stereodet/report/html_report.h"
#include "stereodet/util/strings.h"

namespace stereodet::cli {

namespace {

struct ReportArgs {
  ReportOptions options;
  std::vector<std::string> results;
  std::string labels;  // comma separated
  bool no_png = false;
};

void RunReport(const ReportArgs& a) {
  ReportOptions options = a.options;
  for (const std::string& r : a.results) options.results.emplace_back(r);
  std::stringstream labels(a.labels);
  for (std::string label; std::getline(labels, label, ',');) options.labels.push_back(label);
  options.png = !a.no_png;
  const ReportResult result = WriteReport(options);
  for (const std::string& note : result.notes) fmt::print("note: {}\n", note);
  if (result.num_views > 0) {
    fmt::print("report: {} frame views of the worst frames (views/)\n", result.num_views);
  }
  fmt::print("report: {} figures ({}), {} files\n", result.num_figures,
             result.png ? "SVG and PNG" : "SVG", result.files.size());
  fmt::print("open {}\n", result.index.string());
}

struct ViewArgs {
  FrameViewsOptions options;
  std::string results;
  std::string frames;   // comma separated
  std::string classes;  // comma separated
  std::string difficulty = DifficultyName(FrameViewsOptions().difficulty);
  bool no_png = false;
  bool quiet = false;
};

std::vector<std::string> CommaList(const std::string& text) {
  std::vector<std::string> out;
  for (std::string_view item : Split(text, ',')) {
    if (!Trim(item).empty()) out.emplace_back(Trim(item));
  }
  return out;
}

void RunView(const ViewArgs& a) {
  FrameViewsOptions options = a.options;
  options.results = a.results;
  options.frames = CommaList(a.frames);
  options.classes = CommaList(a.classes);
  const std::optional<Difficulty> difficulty = ParseDifficulty(a.difficulty);
  if (!difficulty) {
    throw std::invalid_argument("--difficulties: unknown '" + a.difficulty +
                                "' (one of easy, moderate, hard)");
  }
  options.difficulty = *difficulty;
  options.png = !a.no_png;
  options.progress.stream = a.quiet ? nullptr : stderr;
  const FrameViewsResult result = WriteFrameViews(options);
  for (const std::string& note : result.notes) fmt::print("note: {}\n", note);
  for (const WrittenFrameView& v : result.views) {
    fmt::print("{} {} ({}: TP {} FP {} FN {}): {}\n", v.frame_id, ViewCellName(v.cell), v.reason,
               v.tp, v.fp, v.fn, v.image_png.empty() ? v.image_svg : v.image_png);
  }
  const std::filesystem::path out = options.out.empty() ? options.results / "views" : options.out;
  fmt::print("view: {} frame view(s), {} files in {}\n", result.views.size(), result.files.size(),
             out.string());
}

}  // namespace

void AddViewCommand(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* view = app.add_subcommand("view", CommandDescription("view"));
  view->add_option("results", args->results,
                   "a results folder of `stereodet eval --out RESULTS --records` (results.json and "
                   "matches.csv; the frames are read again from the folders it names)")
      ->required();
  view->add_option("--frames", args->frames,
                   "frame ids, comma separated (default: the worst frames, --worst)");
  view->add_option(
          "--worst", args->options.worst,
          "without --frames: this many frames with most FNs and as many with most FPs, per "
          "class")
      ->capture_default_str();
  view->add_option("--classes", args->classes,
                   "classes, comma separated (default: every evaluated class)");
  // Spelled as eval spells them (--metrics, --difficulties), one value each here: a view shows
  // one cell. The singular spelling works too.
  view->add_option("--metrics,--metric", args->options.metric,
                   "the cell's overlap kind, one of 2d, bev, 3d (default: the first evaluated)");
  view->add_option("--difficulties,--difficulty", args->difficulty,
                   "the cell's difficulty, one of easy, moderate, hard")
      ->capture_default_str();
  view->add_option("--min-score", args->options.view.min_score,
                   "draw only detections scoring at least this (labels are always drawn)");
  view->add_option("--top-k", args->options.view.top_k,
                   "draw at most this many detections a view, the highest scores (0 = all)")
      ->capture_default_str();
  view->add_option("--points", args->options.points,
                   "point clouds (.bin, velodyne frame) for the bird's-eye view instead of "
                   "DATASET/velodyne: a folder of scans, or the output folder of `stereodet "
                   "stereo --encode points`");
  view->add_option("--out", args->options.out,
                   "where the views go (default: RESULTS/views; files replaced atomically)");
  view->add_flag("--no-png", args->no_png, "SVG views only");
  view->add_option("--png-scale", args->options.png_scale, "PNG pixels per SVG (image) pixel")
      ->capture_default_str();
  view->add_option("--bev-side", args->options.view.bev_side_m,
                   "bird's-eye view: x from -this to +this (m)")
      ->capture_default_str();
  view->add_option("--bev-forward", args->options.view.bev_forward_m,
                   "bird's-eye view: z from 0 to this (m)")
      ->capture_default_str();
  view->add_option("--bev-px-per-m", args->options.view.bev_px_per_m,
                   "bird's-eye view: SVG pixels per metre")
      ->capture_default_str();
  view->add_option("--bev-cell", args->options.view.bev_cell_m,
                   "bird's-eye view: points are drawn as occupied cells of this size (m)")
      ->capture_default_str();
  view->add_flag("--quiet", args->quiet, "no progress line");
  view->callback([args] { RunView(*args); });
}

void AddReportCommand(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* report = app.add_subcommand("report", CommandDescription("report"));
  report
      ->add_option("results", args->results,
                   "results folders of `stereodet eval --out` (several: overlaid, one colour each)")
      ->required();
  report->add_option("--out", args->options.out,
                     "the report folder (default with one results folder: RESULTS/report; replaced "
                     "whole; a folder of other files is refused)");
  report->add_option("--labels", args->labels,
                     "names in legends and tables, comma separated, one per results folder "
                     "(default: the folders' names)");
  report->add_flag("--no-png", args->no_png, "SVG figures only");
  report->add_option("--png-scale", args->options.png_scale, "PNG pixels per SVG pixel")
      ->capture_default_str();
  report
      ->add_option("--worst-frames", args->options.worst_frames,
                   "frame views of this many frames with most FNs and as many with most FPs per "
                   "class, for results folders with matches.csv (eval --records); 0: none")
      ->capture_default_str();
  report->callback([args] { RunReport(*args); });
}

}  // namespace stereodet::cli
