// `stereodet eval`: KITTI-compatible AP and the corrected safety metrics.
//   stereodet eval --gt DIR --det DIR [--split FILE] [--classes ..] [--metrics 2d,bev,3d]
//                  [--matcher kitti|optimal|voc] [--filter COND] [--filter-mode naive|stable]
//                  [--overlaps strict,loose] [--score-transform none|sigmoid] [--lenient]
//                  [--out DIR [--records]]
//   stereodet eval sweep --gt DIR --det DIR --filter min-area --from 0 --to 200 --step 5
//                  [--out DIR]
//   stereodet eval compare --gt DIR --det DIR --det-b DIR [--calib FILE]
//                  [--disparity-error-px 1]
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/eval/compare.h"
#include "stereodet/eval/eval_input.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/report/eval_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
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
  std::string compat = "devkit";
  std::string filter;
  std::string filter_mode = "stable";
  double score_threshold = -std::numeric_limits<double>::infinity();
  std::string score_transform = ScoreTransformName(EvalOptions().score_transform);
  bool loose = false;
  std::string overlaps;  // empty: strict, or loose with --loose
  bool lenient = false;
  bool all_classes = false;
  int calibration_bins = 10;
  double distance_bin_m = 5.0;
  double max_distance_m = 80.0;
  std::string out;
  bool records = false;
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
  cmd->add_option("--compat", a->compat,
                  "devkit | openpcdet (kitti matcher: OpenPCDet's kitti_object_eval_python numbers, "
                  "and its printout)")
      ->capture_default_str();
  if (with_filter) {
    cmd->add_option("--filter", a->filter, "filter, e.g. min-area=100,max-distance=40");
  }
  cmd->add_option("--filter-mode", a->filter_mode, "naive | stable")->capture_default_str();
  cmd->add_option("--score-threshold", a->score_threshold,
                  "operating point for TP/FP/FN, Brier, calibration, filters (default: all)");
  cmd->add_option("--score-transform", a->score_transform,
                  "none | sigmoid (logit scores): applied for Brier and ECE only")
      ->capture_default_str();
  cmd->add_option("--overlaps", a->overlaps,
                  "KITTI overlap sets, e.g. strict,loose (eval only; sweep/compare take one) "
                  "(default strict)");
  cmd->add_flag("--loose", a->loose,
                "KITTI's loose BEV/3D thresholds (0.5/0.25/0.25): --overlaps loose");
  cmd->add_flag("--lenient", a->lenient,
                "skip malformed label/detection lines, count and list them");
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

// The overlap sets of --overlaps (and --loose, its alias for loose), in the order given.
std::vector<OverlapSet> OverlapSets(const EvalArgs& a) {
  std::vector<OverlapSet> sets;
  for (const std::string& name : SplitList(a.overlaps)) {
    const auto set = ParseOverlapSet(name);
    STEREODET_CHECK(set.has_value()) << "--overlaps: unknown '" << name << "' (strict, loose)";
    STEREODET_CHECK(std::find(sets.begin(), sets.end(), *set) == sets.end())
        << "--overlaps: '" << name << "' given twice";
    sets.push_back(*set);
  }
  if (a.loose) {
    STEREODET_CHECK(sets.empty() || (sets.size() == 1 && sets[0] == OverlapSet::kLoose))
        << "--loose is --overlaps loose; give one of them";
    sets = {OverlapSet::kLoose};
  }
  if (sets.empty()) sets.push_back(OverlapSet::kStrict);
  return sets;
}

EvalOptions MakeOptions(const EvalArgs& a, OverlapSet overlaps) {
  STEREODET_CHECK(!a.gt.empty()) << "--gt is required";
  STEREODET_CHECK(!a.det.empty()) << "--det is required";
  EvalOptions o;
  o.classes.clear();
  const auto compat = ParseEvalCompat(a.compat);
  STEREODET_CHECK(compat.has_value())
      << "--compat: unknown '" << a.compat << "' (devkit, openpcdet)";
  o.compat = *compat;
  const bool loose = overlaps == OverlapSet::kLoose;
  for (const std::string& name : SplitList(a.classes)) {
    for (const ClassSpec& c : o.classes) {
      STEREODET_CHECK(!EqualsIgnoreCase(c.name, name))
          << "--classes: '" << name << "' given twice (as '" << c.name << "')";
    }
    o.classes.push_back(o.compat == EvalCompat::kOpenPcdet ? OpenPcdetClassSpec(name, loose)
                                                           : KittiClassSpec(name, loose));
  }
  o.metrics.clear();
  for (const std::string& m : SplitList(a.metrics)) {
    const auto kind = ParseOverlapKind(m);
    STEREODET_CHECK(kind.has_value()) << "--metrics: unknown '" << m << "' (2d, bev, 3d)";
    o.metrics.push_back(*kind);
  }
  o.difficulties.clear();
  for (const std::string& d : SplitList(a.difficulties)) {
    const auto difficulty = ParseDifficulty(d);
    STEREODET_CHECK(difficulty.has_value())
        << "--difficulties: unknown '" << d << "' (easy, moderate, hard)";
    o.difficulties.push_back(*difficulty);
  }
  const auto matcher = ParseMatcher(a.matcher);
  STEREODET_CHECK(matcher.has_value()) << "--matcher: unknown '" << a.matcher << "' (kitti, optimal, voc)";
  o.matcher = *matcher;
  const auto mode = ParseFilterMode(a.filter_mode);
  STEREODET_CHECK(mode.has_value()) << "--filter-mode: unknown '" << a.filter_mode << "' (naive, stable)";
  o.filter.mode = *mode;
  if (!a.filter.empty()) o.filter.conditions = ParseFilterConditions(a.filter);
  o.score_threshold = a.score_threshold;
  const auto transform = ParseScoreTransform(a.score_transform);
  STEREODET_CHECK(transform.has_value())
      << "--score-transform: unknown '" << a.score_transform << "' (none, sigmoid)";
  o.score_transform = *transform;
  o.require_detections = !a.all_classes;
  o.calibration_bins = a.calibration_bins;
  o.distance_bin_m = a.distance_bin_m;
  o.max_distance_m = a.max_distance_m;
  o.num_threads = a.threads;
  o.Check();
  return o;
}

// One overlap set for eval sweep and eval compare.
EvalOptions MakeSingleOptions(const EvalArgs& a) {
  const std::vector<OverlapSet> sets = OverlapSets(a);
  STEREODET_CHECK(sets.size() == 1) << "--overlaps: this command takes one overlap set";
  return MakeOptions(a, sets[0]);
}

struct LoadedInput {
  std::vector<EvalFrame> frames;
  EvalRunInfo info;
};

// LoadEvalFrames, its notices on `notices` (at most kMaxListed skipped lines listed; all of them go
// to results.json).
LoadedInput LoadInput(const EvalArgs& a, const std::string& det, std::FILE* notices = stdout) {
  EvalInputOptions options;
  options.gt = a.gt;
  options.det = det;
  options.split = a.split;
  options.lenient = a.lenient;
  options.num_threads = a.threads;
  EvalInput input = LoadEvalFrames(options);
  for (const std::string& notice : input.Notices()) fmt::print(notices, "{}\n", notice);
  constexpr size_t kMaxListed = 10;
  for (size_t i = 0; i < std::min(kMaxListed, input.skipped_lines.size()); ++i) {
    fmt::print(notices, "  {}\n", input.skipped_lines[i]);
  }
  if (input.skipped_lines.size() > kMaxListed) {
    fmt::print(notices, "  ... and {} more (all in results.json with --out)\n",
               input.skipped_lines.size() - kMaxListed);
  }
  LoadedInput in;
  in.frames = std::move(input.frames);
  in.info.tool_version = STEREODET_VERSION;
  in.info.gt_path = a.gt;
  in.info.det_path = det;
  in.info.split_path = a.split;
  in.info.frames_without_detections = std::move(input.frames_without_detections);
  in.info.lenient = a.lenient;
  in.info.ignored_files = std::move(input.ignored_files);
  in.info.skipped_lines = std::move(input.skipped_lines);
  in.info.input_hash = input.input_hash;
  return in;
}

// The command line of this process (/proc/self/cmdline), arguments joined by spaces, those with
// spaces or quotes in single quotes. Empty where /proc is not there.
std::string ProcessCommandLine() {
  // /proc files report size 0, so read to the end rather than by size.
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  if (!in) return {};
  const std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string out;
  for (std::string_view arg : Split(raw, '\0')) {
    if (arg.empty()) continue;
    if (!out.empty()) out += ' ';
    if (arg.find_first_of(" \t'\"") == std::string_view::npos) {
      out += arg;
    } else {
      out += '\'';
      for (const char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

void RunEval(const EvalArgs& a) {
  STEREODET_CHECK(!a.records || !a.out.empty())
      << "--records needs --out (it writes OUT/matches.csv)";
  std::vector<EvalRun> runs;
  for (const OverlapSet set : OverlapSets(a)) {
    runs.push_back(EvalRun{MakeOptions(a, set), {}});
    runs.back().options.keep_records = a.records;
  }
  // Refuse a folder of something else before the work, not after it.
  std::optional<StagedFolder> out;
  if (!a.out.empty()) out.emplace(a.out, "results.json");
  LoadedInput in = LoadInput(a, a.det);
  in.info.command_line = ProcessCommandLine();
  double seconds = 0.0;
  for (EvalRun& run : runs) {
    run.result = Evaluate(in.frames, run.options);
    seconds += run.result.seconds;
  }
  fmt::print("{}", FormatEvalTable(runs));
  if (runs.front().options.compat == EvalCompat::kOpenPcdet) {
    // OpenPCDet prints both overlap sets itself: once, whatever --overlaps says.
    fmt::print("\nas OpenPCDet's get_official_eval_result prints it:\n{}",
               OpenPcdetPrintout(in.frames, runs.front().options));
  }
  fmt::print("evaluated in {:.3f} s\n", seconds);
  if (out) {
    size_t num_files = WriteEvalReport(out->path(), runs, in.info).size();
    if (a.records) {
      for (const EvalRun& run : runs) {
        // One file per overlap set when there are several, named as the curve files are.
        const std::string name =
            runs.size() == 1 ? std::string("matches.csv")
                             : fmt::format("matches_{}.csv", DescribeOverlaps(run.options.classes));
        const int64_t rows = WriteMatchRecordsCsv(out->path() / name, run.result, in.frames);
        ++num_files;
        fmt::print("per-detection records: {} rows in {}\n", rows, name);
      }
    }
    out->Commit();
    fmt::print("wrote {} files to {}\n", num_files, a.out);
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
  const EvalOptions options = MakeSingleOptions(fixed);
  const auto bound = ParseFilterBound(s.bound);
  STEREODET_CHECK(bound.has_value()) << "--filter: unknown '" << s.bound << "' (e.g. min-area)";
  // The CSV may go to stdout: the notices go to stderr then.
  LoadedInput in = LoadInput(a, a.det, a.out.empty() ? stderr : stdout);
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
  EvalOptions options = MakeSingleOptions(a);
  LoadedInput in_a = LoadInput(a, a.det);
  LoadedInput in_b = LoadInput(a, c.det_b);
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
  eval->add_option(
      "--out", args->out,
      "write results.json and CSVs here (one run per folder: an earlier run's folder is "
      "replaced whole; a folder of other files is refused)");
  eval->add_flag("--records", args->records,
                 "also write OUT/matches.csv: what every detection and label counts as, per class, "
                 "metric and difficulty (docs/metrics.md)");
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
