// `stereodet eval`: KITTI-compatible AP and the corrected safety metrics.
//   stereodet eval --gt DIR --det DIR [--split FILE] [--classes ..] [--metrics 2d,bev,3d]
//                  [--matcher kitti|optimal|voc] [--filter COND] [--filter-mode naive|stable] [--out DIR]
//   stereodet eval sweep --gt DIR --det DIR --filter min-area --from 0 --to 200 --step 5 [--out DIR]
//   stereodet eval compare --gt DIR --det DIR --det-b DIR [--calib FILE] [--disparity-error-px 1]
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "stereodet/cli/commands.h"
#include "stereodet/eval/compare.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/report/eval_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/strings.h"

#ifndef STEREODET_VERSION
#define STEREODET_VERSION "unknown"
#endif

namespace stereodet::cli {

namespace {

namespace fs = std::filesystem;

struct EvalArgs {
  std::string gt, det, split;
  std::string classes = "Car,Pedestrian,Cyclist";
  std::string metrics = "2d,bev,3d";
  std::string difficulties = "easy,moderate,hard";
  std::string matcher = "kitti";
  std::string filter;
  std::string filter_mode = "stable";
  double score_threshold = -std::numeric_limits<double>::infinity();
  bool loose = false;
  bool all_classes = false;
  int calibration_bins = 10;
  double distance_bin_m = 5.0;
  double max_distance_m = 80.0;
  std::string out;
  int threads = 0;
};

// The common options of eval, eval sweep and eval compare.
// --gt and --det are checked when the command runs (not CLI11-required, so that `eval sweep ...`
// does not demand them of `eval`).
void AddCommonOptions(CLI::App* cmd, EvalArgs* a, bool with_filter) {
  cmd->add_option("--gt", a->gt, "labels: a KITTI root (with training/label_2) or a folder of .txt");
  cmd->add_option("--det", a->det, "detections: a folder of .txt (or with data/ inside, devkit style)");
  cmd->add_option("--split", a->split, "frame ids, one per line (or a name in ROOT/ImageSets)");
  cmd->add_option("--classes", a->classes, "classes, comma separated")->capture_default_str();
  cmd->add_option("--metrics", a->metrics, "overlap kinds: 2d,bev,3d")->capture_default_str();
  cmd->add_option("--difficulties", a->difficulties, "easy,moderate,hard")->capture_default_str();
  cmd->add_option("--matcher", a->matcher, "kitti | optimal | voc")->capture_default_str();
  if (with_filter) {
    cmd->add_option("--filter", a->filter, "filter, e.g. min-area=100,max-distance=40");
  }
  cmd->add_option("--filter-mode", a->filter_mode, "naive | stable")->capture_default_str();
  cmd->add_option("--score-threshold", a->score_threshold,
                  "operating point for TP/FP/FN, Brier, calibration, filters (default: all)");
  cmd->add_flag("--loose", a->loose, "KITTI's loose BEV/3D thresholds (0.5/0.25/0.25)");
  cmd->add_flag("--all-classes", a->all_classes,
                "evaluate classes without any detection too (the devkit skips them)");
  cmd->add_option("--calibration-bins", a->calibration_bins, "reliability bins")->capture_default_str();
  cmd->add_option("--distance-bin", a->distance_bin_m, "localization bins, m")->capture_default_str();
  cmd->add_option("--max-distance", a->max_distance_m, "localization range, m")->capture_default_str();
  cmd->add_option("--threads", a->threads, "worker threads (0 = all)")->capture_default_str();
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  for (std::string_view part : Split(text, ',')) {
    part = Trim(part);
    if (!part.empty()) out.emplace_back(part);
  }
  return out;
}

EvalOptions MakeOptions(const EvalArgs& a) {
  STEREODET_CHECK(!a.gt.empty()) << "--gt is required";
  STEREODET_CHECK(!a.det.empty()) << "--det is required";
  EvalOptions o;
  o.classes.clear();
  for (const std::string& name : SplitList(a.classes)) o.classes.push_back(KittiClassSpec(name, a.loose));
  o.metrics.clear();
  for (const std::string& m : SplitList(a.metrics)) {
    const auto kind = ParseOverlapKind(m);
    STEREODET_CHECK(kind.has_value()) << "--metrics: unknown '" << m << "' (2d, bev, 3d)";
    o.metrics.push_back(*kind);
  }
  o.difficulties.clear();
  for (const std::string& d : SplitList(a.difficulties)) {
    if (EqualsIgnoreCase(d, "easy")) o.difficulties.push_back(Difficulty::kEasy);
    else if (EqualsIgnoreCase(d, "moderate")) o.difficulties.push_back(Difficulty::kModerate);
    else if (EqualsIgnoreCase(d, "hard")) o.difficulties.push_back(Difficulty::kHard);
    else STEREODET_THROW_ARG() << "--difficulties: unknown '" << d << "' (easy, moderate, hard)";
  }
  const auto matcher = ParseMatcher(a.matcher);
  STEREODET_CHECK(matcher.has_value()) << "--matcher: unknown '" << a.matcher << "' (kitti, optimal, voc)";
  o.matcher = *matcher;
  const auto mode = ParseFilterMode(a.filter_mode);
  STEREODET_CHECK(mode.has_value()) << "--filter-mode: unknown '" << a.filter_mode << "' (naive, stable)";
  o.filter.mode = *mode;
  if (!a.filter.empty()) o.filter.conditions = ParseFilterConditions(a.filter);
  o.score_threshold = a.score_threshold;
  o.require_detections = !a.all_classes;
  o.calibration_bins = a.calibration_bins;
  o.distance_bin_m = a.distance_bin_m;
  o.max_distance_m = a.max_distance_m;
  o.num_threads = a.threads;
  o.Check();
  return o;
}

fs::path LabelDir(const fs::path& p) {
  if (fs::is_directory(p / "training" / "label_2")) return p / "training" / "label_2";
  if (fs::is_directory(p / "label_2")) return p / "label_2";
  STEREODET_CHECK_IO(fs::is_directory(p)) << "--gt: " << p << " is not a folder";
  return p;
}

fs::path DetectionDir(const fs::path& p) {
  if (fs::is_directory(p / "data")) return p / "data";
  STEREODET_CHECK_IO(fs::is_directory(p)) << "--det: " << p << " is not a folder";
  return p;
}

std::set<std::string> TxtStems(const fs::path& dir) {
  std::set<std::string> stems;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && e.path().extension() == ".txt" && name[0] != '.') {
      stems.insert(e.path().stem().string());
    }
  }
  return stems;
}

std::vector<std::string> ReadIds(const fs::path& gt_root, const std::string& split) {
  if (fs::is_directory(gt_root / "training")) return KittiDataset(gt_root).ReadSplit(split);
  std::vector<std::string> ids;
  const std::string text = ReadFile(split);
  int line_no = 0;
  for (std::string_view line : Split(text, '\n')) {
    ++line_no;
    line = Trim(line);
    if (line.empty()) continue;
    const bool digits = std::all_of(line.begin(), line.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits) throw ParseError(split, line_no, "frame id", "'" + std::string(line) + "' is not a frame id");
    ids.emplace_back(line);
  }
  return ids;
}

struct LoadedInput {
  std::vector<EvalFrame> frames;
  EvalRunInfo info;
};

LoadedInput LoadInput(const std::string& gt, const std::string& det, const std::string& split,
                      int threads) {
  LoadedInput in;
  in.info.tool_version = STEREODET_VERSION;
  in.info.gt_path = gt;
  in.info.det_path = det;
  in.info.split_path = split;
  const fs::path label_dir = LabelDir(gt);
  const fs::path det_dir = DetectionDir(det);
  const std::set<std::string> label_stems = TxtStems(label_dir);
  const std::set<std::string> det_stems = TxtStems(det_dir);
  for (const std::string& s : det_stems) {
    STEREODET_CHECK_IO(label_stems.count(s))
        << "detection file " << (det_dir / (s + ".txt")).string() << " has no label file in "
        << label_dir.string();
  }
  std::vector<std::string> ids;
  if (split.empty()) {
    ids.assign(label_stems.begin(), label_stems.end());
  } else {
    ids = ReadIds(gt, split);
    for (const std::string& id : ids) {
      STEREODET_CHECK_IO(label_stems.count(id))
          << "split " << split << ": frame " << id << " has no label file in " << label_dir.string();
    }
  }
  STEREODET_CHECK_IO(!ids.empty()) << "no frame to evaluate in " << label_dir.string();
  in.frames.resize(ids.size());
  std::vector<uint8_t> missing(ids.size(), 0);
  ParallelFor(ids.size(), [&](size_t i) {
    EvalFrame& f = in.frames[i];
    f.id = ids[i];
    f.labels = ReadObjects(label_dir / (ids[i] + ".txt"), {ObjectFileKind::kLabel, false}).objects;
    if (det_stems.count(ids[i])) {
      f.detections = ReadObjects(det_dir / (ids[i] + ".txt"), {ObjectFileKind::kDetection, false}).objects;
    } else {
      missing[i] = 1;
    }
  }, threads);
  for (size_t i = 0; i < ids.size(); ++i) {
    if (missing[i]) in.info.frames_without_detections.push_back(ids[i]);
  }
  return in;
}

void RunEval(const EvalArgs& a) {
  const EvalOptions options = MakeOptions(a);
  LoadedInput in = LoadInput(a.gt, a.det, a.split, a.threads);
  const EvalResult result = Evaluate(in.frames, options);
  fmt::print("{}", FormatEvalTable(result, options));
  if (!in.info.frames_without_detections.empty()) {
    fmt::print("frames without a detection file (no detections): {}\n",
               in.info.frames_without_detections.size());
  }
  fmt::print("evaluated in {:.3f} s\n", result.seconds);
  if (!a.out.empty()) {
    const auto written = WriteEvalReport(a.out, result, options, in.info);
    fmt::print("wrote {} files to {}\n", written.size(), a.out);
  }
}

struct SweepArgs {
  std::string bound;
  double from = 0, to = 200, step = 5;
  std::string where;
};

void RunSweep(const EvalArgs& a, const SweepArgs& s) {
  EvalArgs fixed = a;
  fixed.filter = s.where;
  const EvalOptions options = MakeOptions(fixed);
  const auto bound = ParseFilterBound(s.bound);
  STEREODET_CHECK(bound.has_value()) << "--filter: unknown '" << s.bound << "' (e.g. min-area)";
  LoadedInput in = LoadInput(a.gt, a.det, a.split, a.threads);
  const std::vector<SweepRow> rows = FilterSweep(in.frames, options, *bound, s.from, s.to, s.step);
  const std::string csv = FormatSweepCsv(rows, *bound);
  if (a.out.empty()) {
    fmt::print("{}", csv);
  } else {
    WriteFileAtomically(fs::path(a.out) / "sweep.csv", csv);
    fmt::print("wrote {} rows to {}\n", rows.size(), (fs::path(a.out) / "sweep.csv").string());
  }
}

struct CompareArgs {
  std::string det_b;
  std::string calib;
  double disparity_error_px = 1.0;
};

void RunCompare(const EvalArgs& a, const CompareArgs& c) {
  EvalOptions options = MakeOptions(a);
  LoadedInput in_a = LoadInput(a.gt, a.det, a.split, a.threads);
  LoadedInput in_b = LoadInput(a.gt, c.det_b, a.split, a.threads);
  const EvalResult ra = Evaluate(in_a.frames, options);
  const EvalResult rb = Evaluate(in_b.frames, options);
  const Calibration calib = c.calib.empty() ? KittiLikeCalibration() : ReadCalibration(c.calib);
  const double baseline_m = calib.BaselineM(), focal_px = calib.FocalPx();
  fmt::print("A = {}\nB = {}\nstereo model: dz = z^2 / (b f) * dd, b = {:.4f} m, f = {:.2f} px, dd = {} px{}\n",
             a.det, c.det_b, baseline_m, focal_px, c.disparity_error_px,
             c.calib.empty() ? " (KITTI-like calibration)" : "");
  CompareOptions compare_options;
  compare_options.baseline_m = baseline_m;
  compare_options.focal_px = focal_px;
  compare_options.disparity_error_px = c.disparity_error_px;
  const std::vector<CompareRow> rows = CompareLocalization(ra, rb, compare_options);
  for (size_t k = 0; k < rows.size(); ++k) {
    const CompareRow& r = rows[k];
    if (k == 0 || rows[k - 1].class_name != r.class_name || rows[k - 1].metric != r.metric ||
        rows[k - 1].difficulty != r.difficulty) {
      fmt::print("\n{} {} {}: mean |depth error| of matched pairs (m)\n", r.class_name,
                 OverlapKindName(r.metric), DifficultyName(r.difficulty));
      fmt::print("  {:>11} {:>7} {:>8} {:>7} {:>8} {:>8} {:>8}\n", "depth", "n A", "A", "n B", "B", "B - A",
                 "model");
    }
    fmt::print("  {:>4g}-{:<4g} m {:>7} {:>8} {:>7} {:>8} {:>8} {:>8.3f}\n", r.lower_m, r.upper_m, r.count_a,
               FormatNumber(r.abs_depth_error_mean_a_m, 3), r.count_b,
               FormatNumber(r.abs_depth_error_mean_b_m, 3), FormatNumber(r.difference_b_minus_a_m, 3),
               r.model_depth_error_m);
  }
  const std::string csv = FormatCompareCsv(rows);
  if (!a.out.empty()) {
    WriteFileAtomically(fs::path(a.out) / "compare.csv", csv);
    fmt::print("\nwrote {}\n", (fs::path(a.out) / "compare.csv").string());
  }
}

}  // namespace

void AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* eval = app.add_subcommand("eval", CommandDescription("eval"));
  AddCommonOptions(eval, args.get(), true);
  eval->add_option("--out", args->out, "write results.json and CSVs here");
  eval->require_subcommand(0, 1);
  // Options of eval itself must come before a sub-subcommand; the sub-subcommands have their own.
  eval->fallthrough(false);

  auto sweep_common = std::make_shared<EvalArgs>();
  auto sweep_args = std::make_shared<SweepArgs>();
  CLI::App* sweep = eval->add_subcommand("sweep", "precision/recall of the naive and the stable filter "
                                                  "along a sweep of one filter bound");
  AddCommonOptions(sweep, sweep_common.get(), false);
  sweep->add_option("--filter", sweep_args->bound, "the swept bound, e.g. min-area")->required();
  sweep->add_option("--from", sweep_args->from)->capture_default_str();
  sweep->add_option("--to", sweep_args->to)->capture_default_str();
  sweep->add_option("--step", sweep_args->step)->capture_default_str();
  sweep->add_option("--where", sweep_args->where, "fixed extra filter, e.g. max-distance=40");
  sweep->add_option("--out", sweep_common->out, "write sweep.csv here (default: stdout)");
  sweep->callback([sweep_common, sweep_args] { RunSweep(*sweep_common, *sweep_args); });

  auto compare_common = std::make_shared<EvalArgs>();
  auto compare_args = std::make_shared<CompareArgs>();
  CLI::App* compare = eval->add_subcommand("compare", "3D localization error of two detection sets "
                                                      "(e.g. stereo vs LiDAR) beside the stereo model");
  AddCommonOptions(compare, compare_common.get(), true);
  compare->add_option("--det-b", compare_args->det_b, "the second detection folder")->required();
  compare->add_option("--calib", compare_args->calib, "a KITTI calib file for b and f (default KITTI-like)");
  compare->add_option("--disparity-error-px", compare_args->disparity_error_px)->capture_default_str();
  compare->add_option("--out", compare_common->out, "write compare.csv here");
  compare->callback([compare_common, compare_args] { RunCompare(*compare_common, *compare_args); });

  eval->callback([eval, sweep, compare, args] {
    if (eval->got_subcommand(sweep) || eval->got_subcommand(compare)) return;
    RunEval(*args);
  });
}

}  // namespace stereodet::cli
