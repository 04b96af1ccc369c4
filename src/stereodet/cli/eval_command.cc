// `stereodet eval`: KITTI-compatible AP and the corrected safety metrics.
//   stereodet eval --gt DIR --det DIR [--split FILE] [--classes ..] [--metrics 2d,bev,3d]
//                  [--matcher kitti|optimal|voc] [--filter COND] [--filter-mode naive|stable]
//                  [--overlaps strict,loose] [--score-transform none|sigmoid] [--lenient]
//                  [--out DIR [--records] [--report]] [--errors] [--bootstrap N [--bootstrap-seed
//                  S]
//                  [--bootstrap-confidence C]]
//   stereodet eval sweep --gt DIR --det DIR --filter min-area --from 0 --to 200 --step 5
//                  [--out DIR]
//   stereodet eval compare --gt DIR --det DIR --det-b DIR [--calib FILE]
//                  [--disparity-error-px 1] [--bootstrap N ...] [--out DIR]
//   stereodet eval --coco-gt FILE --coco-det FILE [--coco-det-b FILE] [--coco-honor-ignore]
//                  [--matcher coco|optimal] [--bootstrap N ...]
//                  [--coco-brier [--score-threshold S] [--score-transform T]
//                  [--calibration-bins N]] [--out DIR] [--threads N]
//                  (COCO mode: pycocotools' COCOeval for bbox, docs/metrics.md)
//   stereodet eval --shard K/N --gt DIR --det DIR --out SHARD_DIR ...   (docs/scale.md)
//   stereodet eval merge SHARD_DIR... --out DIR ...  (the shards' evaluation flags)
//   stereodet eval sweep|compare --shards SHARD_DIR... [--shards-b SHARD_DIR...] ...  (the frames
//   from eval shards instead of --gt/--det)
// Each is one library call (pipelines/evaluation.h: RunEvaluation, RunEvaluationSweep,
// RunEvaluationCompare; pipelines/coco_evaluation.h: RunCocoEvaluation); this file binds the
// flags to their options and prints the results.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/calibration_fit.h"
#include "stereodet/eval/error_analysis.h"
#include "stereodet/eval/eval_input.h"
#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/pipelines/coco_evaluation.h"
#include "stereodet/pipelines/evaluation.h"
#include "stereodet/report/bootstrap_report.h"
#include "stereodet/report/eval_report.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/version.h"

namespace stereodet::cli {

namespace {

namespace fs = std::filesystem;

// The names of a list joined by commas, for the defaults the help shows.
template <typename T, typename NameFn>
std::string JoinNames(const std::vector<T>& items, NameFn name) {
  std::string out;
  for (const T& item : items) {
    if (!out.empty()) out += ',';
    out += name(item);
  }
  return out;
}

std::string ToLowerAscii(std::string text) {
  for (char& c : text) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return text;
}

// The flags of eval, eval sweep and eval compare: scalars bound straight to the fields of `input`
// and `eval`, lists and names as text that MakeOptions parses into `eval`; defaults from the
// structs.
struct EvalArgs {
  EvalInputOptions input;  // --gt, --det, --split, --lenient
  EvalOptions eval;        // --score-threshold, --calibration-bins, ..., --threads
  std::string classes = JoinNames(EvalOptions().classes, [](const ClassSpec& c) { return c.name; });
  std::string metrics = JoinNames(EvalOptions().metrics, OverlapKindName);
  std::string let_tolerance;  // --let-tolerance FRACTION,MIN_M (empty: LetOptions' defaults)
  std::string let_sensor;     // --let-sensor X,Y,Z (empty: the origin)
  std::string dece_bins;      // --dece-bins S,X,Y,W,H (empty: DeceOptions' defaults)
  std::string image_size;     // --image-size W,H (empty: KITTI's 1242,375)
  std::string difficulties = JoinNames(
      EvalOptions().difficulties, [](Difficulty d) { return ToLowerAscii(DifficultyName(d)); });
  std::string matcher = MatcherName(EvalOptions().matcher);
  std::string compat = EvalCompatName(EvalOptions().compat);
  std::string filter;
  std::string filter_mode = FilterModeName(EvalOptions().filter.mode);
  std::vector<std::string> breakdowns;  // --breakdown AXIS=EDGES, repeatable (eval, eval merge)
  bool breakdown_naive = false;         // --breakdown-naive (eval, eval merge)
  std::string score_transform = ScoreTransformName(EvalOptions().score_transform);
  bool loose = false;
  std::string overlaps;  // empty: strict, or loose with --loose
  bool all_classes = false;
  std::string out;
  bool records = false;
  bool report = false;
  bool devkit_files = false;  // --devkit-files (eval only)
  std::string calibration;    // --calibration FILE (eval, eval merge)
  bool errors = false;        // --errors (eval, eval merge)
  double errors_background = ErrorAnalysisOptions().background_overlap;  // --errors-background
  bool errors_background_given = false;                                  // set by NoteGivenFlags
  std::string method = CalibrationMethodName(CalibrationFitOptions().method);  // calibrate
  bool skip_unfittable = false;                                                // calibrate
  // --bootstrap N, --bootstrap-seed, --bootstrap-confidence (eval, compare, merge); used when
  // --bootstrap was given (bootstrap_given, set by the command's callback).
  BootstrapOptions bootstrap;
  bool bootstrap_given = false;
  bool bootstrap_settings_given = false;  // --bootstrap-seed, -confidence or -method
  std::string bootstrap_method = BootstrapMethodName(BootstrapOptions().method);
  // COCO mode (eval only): --coco-gt, --coco-det, --coco-honor-ignore; out and num_threads come
  // from --out and --threads.
  CocoEvaluationOptions coco;
  bool coco_per_category = false;                // --coco-per-category
  std::string coco_area_ranges = "pycocotools";  // --coco-area-ranges
};

// The bootstrap flags (docs/metrics.md, "Bootstrap intervals").
void AddBootstrapOptions(CLI::App* cmd, EvalArgs* a, const char* what) {
  cmd->add_option("--bootstrap", a->bootstrap.num_resamples,
                  fmt::format("N resamples of the frames (e.g. 1000): {}", what));
  cmd->add_option("--bootstrap-seed", a->bootstrap.seed, "the resamples' seed")
      ->capture_default_str();
  cmd->add_option("--bootstrap-confidence", a->bootstrap.confidence,
                  "the intervals' confidence level, in (0, 1)")
      ->capture_default_str();
  cmd->add_option("--bootstrap-method", a->bootstrap_method,
                  "percentile | bca (bias-corrected and accelerated; its acceleration from a "
                  "jackknife over 100 groups of frames or images; docs/metrics.md)")
      ->capture_default_str();
}

// Records in `a` which bootstrap flags `cmd` got, and --errors-background where `cmd` has it
// (called from the command's callback).
void NoteGivenFlags(const CLI::App* cmd, EvalArgs* a) {
  a->bootstrap_given = cmd->count("--bootstrap") > 0;
  a->bootstrap_settings_given = cmd->count("--bootstrap-seed") > 0 ||
                                cmd->count("--bootstrap-confidence") > 0 ||
                                cmd->count("--bootstrap-method") > 0;
  const CLI::Option* background = cmd->get_option_no_throw("--errors-background");
  a->errors_background_given = background != nullptr && background->count() > 0;
}

// The bootstrap options of the flags: unset without --bootstrap.
std::optional<BootstrapOptions> MakeBootstrapOptions(const EvalArgs& a) {
  if (!a.bootstrap_given) {
    STEREODET_CHECK(!a.bootstrap_settings_given)
        << "--bootstrap-seed, --bootstrap-confidence and --bootstrap-method need --bootstrap N";
    return std::nullopt;
  }
  STEREODET_CHECK(a.bootstrap.num_resamples >= 1 &&
                  a.bootstrap.num_resamples <= kMaxBootstrapResamples)
      << "--bootstrap: resamples must be in [1, " << kMaxBootstrapResamples << "], got "
      << a.bootstrap.num_resamples;
  STEREODET_CHECK(a.bootstrap.confidence > 0 && a.bootstrap.confidence < 1)
      << "--bootstrap-confidence: must be in (0, 1), got " << a.bootstrap.confidence;
  const auto method = ParseBootstrapMethod(a.bootstrap_method);
  STEREODET_CHECK(method.has_value())
      << "--bootstrap-method: unknown '" << a.bootstrap_method << "' (percentile, bca)";
  BootstrapOptions options = a.bootstrap;
  options.method = *method;
  return options;
}

// The common options of eval, eval sweep and eval compare.
// --gt and --det are checked when the command runs (not CLI11-required, so that `eval sweep ...`
// does not demand them of `eval`).
// `det_flag`: the detections' flag ("--det"; calibrate's "--fit").
void AddCommonOptions(CLI::App* cmd, EvalArgs* a, bool with_filter,
                      const std::string& det_flag = "--det") {
  cmd->add_option("--gt", a->input.gt,
                  "labels: a KITTI root (with training/label_2) or a folder of .txt (required, "
                  "except with --shards or in COCO mode)");
  cmd->add_option(det_flag, a->input.det,
                  "detections: a folder of .txt (or with data/ inside, devkit style) (required, "
                  "except with --shards or in COCO mode)");
  cmd->add_option("--split", a->input.split,
                  "frame ids, one per line (or a name in ROOT/ImageSets)");
  cmd->add_option("--classes", a->classes, "classes, comma separated")->capture_default_str();
  cmd->add_option("--metrics", a->metrics,
                  "overlap kinds: 2d,bev,3d and LET-3D-AP's let-bev,let-3d (docs/metrics.md)")
      ->capture_default_str();
  cmd->add_option("--let-tolerance", a->let_tolerance,
                  "let-bev / let-3d: longitudinal tolerance FRACTION,MIN_M, max(FRACTION x range, "
                  "MIN_M) (default 0.1,0.5, Waymo's)");
  cmd->add_option("--let-sensor", a->let_sensor,
                  "let-bev / let-3d: the sensor X,Y,Z in the camera frame, m, whose lines of sight "
                  "the tolerance runs along (default 0,0,0, KITTI's camera 0)");
  cmd->add_option("--dece-bins", a->dece_bins,
                  "D-ECE's bins of the score, box centre x, centre y, width and height (default "
                  "5,5,5,5,5; docs/metrics.md, Calibration)");
  cmd->add_option("--image-size", a->image_size,
                  "the image the 2D boxes are in, W,H px, for D-ECE (default 1242,375, KITTI's)");
  cmd->add_option("--difficulties", a->difficulties, "easy,moderate,hard")->capture_default_str();
  cmd->add_option("--matcher", a->matcher, "kitti | optimal | voc (COCO mode: coco | optimal)")
      ->capture_default_str();
  cmd->add_option(
         "--compat", a->compat,
         "devkit | openpcdet (kitti matcher: OpenPCDet's kitti_object_eval_python numbers, "
         "and its printout)")
      ->capture_default_str();
  if (with_filter) {
    cmd->add_option("--filter", a->filter, "filter, e.g. min-area=100,max-distance=40");
  }
  cmd->add_option("--filter-mode", a->filter_mode, "naive | stable")->capture_default_str();
  cmd->add_option("--score-threshold", a->eval.score_threshold,
                  "operating point for TP/FP/FN, Brier, calibration, filters (default: all)");
  cmd->add_option("--score-transform", a->score_transform,
                  "none | sigmoid (logit scores): applied for Brier and ECE only")
      ->capture_default_str();
  cmd->add_option(
      "--overlaps", a->overlaps,
      fmt::format("KITTI overlap sets, e.g. strict,loose (eval only; sweep/compare take "
                  "one) (default {})",
                  OverlapSetName(OverlapSet::kStrict)));
  cmd->add_flag("--loose", a->loose,
                "KITTI's loose BEV/3D thresholds (0.5/0.25/0.25): --overlaps loose");
  cmd->add_flag("--lenient", a->input.lenient,
                "skip malformed label/detection lines, count and list them");
  cmd->add_option_function<double>(
      "--score", [a](const double& score) { a->input.score_if_missing = score; },
      "read detection lines without a score (15 fields, as labels have) as detections of this "
      "score: `--det LABELS --score 1` checks the evaluation on the labels themselves (refused "
      "without it)");
  cmd->add_flag("--missing-as-empty", a->input.missing_as_empty,
                fmt::format("without --split: evaluate labelled frames that have no detection file "
                            "as frames without detections, even when more than {:.0f}% lack one "
                            "(refused otherwise)",
                            100 * kMaxMissingDetectionShare));
  cmd->add_flag("--all-classes", a->all_classes,
                "evaluate classes without any detection too (the devkit skips them)");
  cmd->add_option("--calibration-bins", a->eval.calibration_bins, "reliability bins")
      ->capture_default_str();
  cmd->add_option("--distance-bin", a->eval.distance_bin_m, "localization bins, m")
      ->capture_default_str();
  cmd->add_option("--max-distance", a->eval.max_distance_m, "localization range, m")
      ->capture_default_str();
  cmd->add_option("--threads", a->eval.num_threads, "worker threads (0 = all)")
      ->capture_default_str();
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  for (std::string_view part : Split(text, ',')) {
    part = Trim(part);
    if (!part.empty()) out.emplace_back(part);
  }
  return out;
}

// `count` finite numbers separated by commas, or a clear error naming `flag`.
std::vector<double> ParseNumbers(const std::string& text, size_t count, const char* flag,
                                 const char* what) {
  std::vector<double> out;
  for (const std::string& part : SplitList(text)) {
    const std::optional<double> v = ParseDouble(part);
    STEREODET_CHECK(v.has_value() && std::isfinite(*v))
        << flag << ": '" << part << "' is not a finite number (" << what << ")";
    out.push_back(*v);
  }
  STEREODET_CHECK(out.size() == count)
      << flag << ": expected " << count << " numbers " << what << ", got '" << text << "'";
  return out;
}

// EvalOptions::let of --let-tolerance and --let-sensor (each empty: its default).
LetOptions ParseLetFlags(const std::string& tolerance, const std::string& sensor) {
  LetOptions let;
  if (!tolerance.empty()) {
    const std::vector<double> v = ParseNumbers(tolerance, 2, "--let-tolerance", "FRACTION,MIN_M");
    let.longitudinal_tolerance_fraction = v[0];
    let.min_longitudinal_tolerance_m = v[1];
  }
  if (!sensor.empty()) {
    const std::vector<double> v = ParseNumbers(sensor, 3, "--let-sensor", "X,Y,Z in metres");
    let.sensor_m = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  try {
    let.Check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--let-tolerance / --let-sensor: ") + e.what());
  }
  return let;
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

// The evaluation options of the flags, with the strict overlap set's class specs (OverlapSetRuns
// makes those of the other sets).
EvalOptions MakeOptions(const EvalArgs& a) {
  STEREODET_CHECK(!a.input.gt.empty()) << "--gt is required";
  STEREODET_CHECK(!a.input.det.empty()) << "--det is required";
  EvalOptions o = a.eval;
  o.classes.clear();
  const auto compat = ParseEvalCompat(a.compat);
  STEREODET_CHECK(compat.has_value())
      << "--compat: unknown '" << a.compat << "' (devkit, openpcdet)";
  o.compat = *compat;
  for (const std::string& name : SplitList(a.classes)) {
    for (const ClassSpec& c : o.classes) {
      STEREODET_CHECK(!EqualsIgnoreCase(c.name, name))
          << "--classes: '" << name << "' given twice (as '" << c.name << "')";
    }
    o.classes.push_back(o.compat == EvalCompat::kOpenPcdet ? OpenPcdetClassSpec(name)
                                                           : KittiClassSpec(name));
  }
  o.metrics.clear();
  for (const std::string& m : SplitList(a.metrics)) {
    const auto kind = ParseOverlapKind(m);
    STEREODET_CHECK(kind.has_value())
        << "--metrics: unknown '" << m << "' (2d, bev, 3d, let-bev, let-3d)";
    o.metrics.push_back(*kind);
  }
  o.let = ParseLetFlags(a.let_tolerance, a.let_sensor);
  if (!a.dece_bins.empty()) {
    const std::vector<double> v = ParseNumbers(a.dece_bins, 5, "--dece-bins", "S,X,Y,W,H");
    for (int d = 0; d < 5; ++d) {
      STEREODET_CHECK(v[d] == std::floor(v[d]) && v[d] >= 1 && v[d] <= 100)
          << "--dece-bins: " << v[d] << " is not a whole number of bins in [1, 100]";
      o.dece.bins[d] = static_cast<int>(v[d]);
    }
  }
  if (!a.image_size.empty()) {
    const std::vector<double> v = ParseNumbers(a.image_size, 2, "--image-size", "W,H in px");
    o.dece.image_width_px = v[0];
    o.dece.image_height_px = v[1];
  }
  o.difficulties.clear();
  for (const std::string& d : SplitList(a.difficulties)) {
    const auto difficulty = ParseDifficulty(d);
    STEREODET_CHECK(difficulty.has_value())
        << "--difficulties: unknown '" << d << "' (easy, moderate, hard)";
    o.difficulties.push_back(*difficulty);
  }
  const auto matcher = ParseMatcher(a.matcher);
  STEREODET_CHECK(matcher.has_value())
      << "--matcher: unknown '" << a.matcher << "' (kitti, optimal, voc)";
  o.matcher = *matcher;
  const auto mode = ParseFilterMode(a.filter_mode);
  STEREODET_CHECK(mode.has_value())
      << "--filter-mode: unknown '" << a.filter_mode << "' (naive, stable)";
  o.filter.mode = *mode;
  if (!a.filter.empty()) o.filter.conditions = ParseFilterConditions(a.filter);
  for (const std::string& text : a.breakdowns) {
    try {
      o.breakdowns.push_back(ParseBreakdown(text));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--breakdown: ") + e.what());
    }
  }
  STEREODET_CHECK(!a.breakdown_naive || !a.breakdowns.empty())
      << "--breakdown-naive recomputes the bins of --breakdown: give --breakdown AXIS=EDGES too";
  o.breakdown_naive = a.breakdown_naive;
  const auto transform = ParseScoreTransform(a.score_transform);
  STEREODET_CHECK(transform.has_value())
      << "--score-transform: unknown '" << a.score_transform << "' (none, sigmoid)";
  o.score_transform = *transform;
  o.require_detections = !a.all_classes;
  o.Check();
  return o;
}

// One overlap set for eval sweep and eval compare.
EvalOptions MakeSingleOptions(const EvalArgs& a) {
  const std::vector<OverlapSet> sets = OverlapSets(a);
  STEREODET_CHECK(sets.size() == 1) << "--overlaps: this command takes one overlap set";
  return OverlapSetRuns(MakeOptions(a), sets).front();
}

// The input options of the flags; --threads is the evaluation's and the reading's.
EvalInputOptions MakeInputOptions(const EvalArgs& a) {
  EvalInputOptions input = a.input;
  input.num_threads = a.eval.num_threads;
  return input;
}

// What LoadEvalFrames noticed, on `stream` (at most kMaxListed skipped lines listed; all of them
// go to results.json).
void PrintNotices(const EvalInput& input, std::FILE* stream = stdout) {
  for (const std::string& notice : input.Notices()) fmt::print(stream, "{}\n", notice);
  constexpr size_t kMaxListed = 10;
  for (size_t i = 0; i < std::min(kMaxListed, input.skipped_lines.size()); ++i) {
    fmt::print(stream, "  {}\n", input.skipped_lines[i]);
  }
  if (input.skipped_lines.size() > kMaxListed) {
    fmt::print(stream, "  ... and {} more (all in results.json with --out)\n",
               input.skipped_lines.size() - kMaxListed);
  }
}

// The error analysis options of --errors / --errors-background: unset without --errors.
std::optional<ErrorAnalysisOptions> MakeErrorOptions(const EvalArgs& a) {
  STEREODET_CHECK(a.errors || !a.errors_background_given) << "--errors-background needs --errors";
  if (!a.errors) return std::nullopt;
  ErrorAnalysisOptions options;
  options.background_overlap = a.errors_background;
  return options;
}

void RunEval(const EvalArgs& a) {
  STEREODET_CHECK(!a.records || !a.out.empty())
      << "--records needs --out (it writes OUT/matches.csv)";
  STEREODET_CHECK(!a.report || !a.out.empty()) << "--report needs --out (it writes OUT/report/)";
  STEREODET_CHECK(!a.devkit_files || !a.out.empty())
      << "--devkit-files needs --out (it writes OUT/stats_*.txt and OUT/plot/)";
  EvaluationOptions options;
  const std::vector<OverlapSet> sets = OverlapSets(a);
  options.runs = OverlapSetRuns(MakeOptions(a), sets);
  options.input = MakeInputOptions(a);
  options.out = a.out;
  options.records = a.records;
  options.report = a.report;
  options.devkit_files = a.devkit_files;
  options.calibration = a.calibration;
  options.bootstrap = MakeBootstrapOptions(a);
  options.errors = MakeErrorOptions(a);
  options.tool_version = StereodetVersion();
  options.command_line = ProcessCommandLine();
  const EvaluationResult result = RunEvaluation(options);
  if (!a.calibration.empty()) {
    fmt::print("calibration {}: {} detection scores replaced\n", a.calibration,
               result.info.calibrated_detections);
  }

  PrintNotices(result.input);
  fmt::print("{}", FormatEvalTable(result.runs));
  if (result.runs.front().options.compat == EvalCompat::kOpenPcdet) {
    // OpenPCDet prints both overlap sets itself: once, whatever --overlaps says.
    fmt::print("\nas OpenPCDet's get_official_eval_result prints it:\n{}",
               OpenPcdetPrintout(result.input.frames, result.runs.front().options));
  }
  fmt::print("evaluated in {:.3f} s\n", result.seconds);
  if (options.bootstrap) fmt::print("bootstrap in {:.3f} s\n", result.bootstrap_seconds);
  if (options.errors) fmt::print("error analysis in {:.3f} s\n", result.errors_seconds);
  if (a.out.empty()) return;
  for (const EvaluationResult::RecordsFile& records : result.records) {
    fmt::print("per-detection records: {} rows in {}\n", records.rows, records.name);
  }
  fmt::print("wrote {} files to {}\n", result.files.size(), a.out);
  for (const std::string& note : result.report_notes) fmt::print("note: {}\n", note);
  if (a.report) fmt::print("report: open {}\n", result.report_index.string());
}

// The flags of `eval` that COCO mode takes; the others are for KITTI-layout data.
bool IsCocoModeFlag(const std::string& name) {
  return name == "--coco-gt" || name == "--coco-det" || name == "--coco-honor-ignore" ||
         name == "--coco-brier" || name == "--matcher" || name == "--score-threshold" ||
         name == "--score-transform" || name == "--calibration-bins" || name == "--out" ||
         name == "--coco-per-category" || name == "--threads" || name == "--help" ||
         name == "--debug" || name == "--coco-det-b" || name == "--bootstrap" ||
         name == "--bootstrap-seed" || name == "--bootstrap-confidence" ||
         name == "--bootstrap-method" || name == "--coco-area-ranges";
}

// The flags that set the operating-point metrics' options: each turns them on.
bool IsCocoOperatingPointFlag(const std::string& name) {
  return name == "--score-threshold" || name == "--score-transform" || name == "--calibration-bins";
}

// `eval --coco-gt FILE --coco-det FILE`: pycocotools' COCOeval for bbox, its summary printed in
// its own layout.
void RunCocoEval(const CLI::App* eval, const EvalArgs& a) {
  for (const CLI::Option* option : eval->get_options()) {
    STEREODET_CHECK(option->count() == 0 || IsCocoModeFlag(option->get_name()))
        << option->get_name()
        << " is a flag of KITTI-layout evaluation; COCO mode (--coco-gt, --coco-det) takes "
           "--out, --threads, --coco-honor-ignore, --coco-area-ranges, --coco-det-b, "
           "--coco-per-category, "
           "--matcher coco|optimal, --coco-brier, --score-threshold, --score-transform, "
           "--calibration-bins and --bootstrap N (--bootstrap-seed, --bootstrap-confidence, "
           "--bootstrap-method)";
  }
  STEREODET_CHECK(!a.coco.gt.empty() && !a.coco.det.empty())
      << "COCO mode needs both --coco-gt FILE and --coco-det FILE";
  CocoEvaluationOptions options = a.coco;
  if (eval->count("--matcher") > 0) {
    const auto matcher = ParseCocoMatcher(a.matcher);
    STEREODET_CHECK(matcher.has_value())
        << "--matcher: COCO mode has the matchers coco (pycocotools' greedy one, the default) "
           "and optimal; got '"
        << a.matcher << "'";
    options.eval.matcher = *matcher;
  }
  STEREODET_CHECK(a.coco_area_ranges == "pycocotools" || a.coco_area_ranges == "stable")
      << "--coco-area-ranges: pycocotools (each range matched on its own, the default) or stable "
         "(every range counted from the matching of range all); got '"
      << a.coco_area_ranges << "'";
  options.eval.stable_area_ranges = a.coco_area_ranges == "stable";
  for (const CLI::Option* option : eval->get_options()) {
    if (option->count() > 0 && IsCocoOperatingPointFlag(option->get_name())) {
      options.eval.score_metrics = true;
    }
  }
  options.bootstrap = MakeBootstrapOptions(a);
  if (options.bootstrap) options.bootstrap->num_threads = a.eval.num_threads;
  if (options.eval.score_metrics) {
    const auto transform = ParseScoreTransform(a.score_transform);
    STEREODET_CHECK(transform.has_value())
        << "--score-transform: unknown '" << a.score_transform << "' (none, sigmoid)";
    options.eval.score_transform = *transform;
    options.eval.score_threshold = a.eval.score_threshold;
    options.eval.calibration_bins = a.eval.calibration_bins;
  }
  options.eval.num_threads = a.eval.num_threads;
  options.out = a.out;
  options.tool_version = StereodetVersion();
  options.command_line = ProcessCommandLine();
  const CocoEvaluationResult run = RunCocoEvaluation(options);
  const CocoEvalResult& r = run.result;
  // Left out as pycocotools leaves them out: worth a line, as they are often a mistake.
  if (r.num_gt_skipped > 0) {
    fmt::print("annotations of an image or category the ground truth does not list, left out: {}\n",
               r.num_gt_skipped);
  }
  if (r.num_detections_skipped > 0) {
    fmt::print("detections of a category the ground truth does not list, left out: {}\n",
               r.num_detections_skipped);
  }
  if (r.options.score_metrics && !r.probability_metrics) {
    fmt::print(
        "note: scores outside [0, 1] are not probabilities: the Brier scores and calibration are "
        "left out (-1); --score-transform sigmoid reads them as logits\n");
  }
  fmt::print("{}", FormatCocoSummary(r));
  if (a.coco_per_category) fmt::print("{}", FormatCocoCategories(r));
  if (run.result_b) {
    fmt::print("{}", FormatCocoCompare(r, *run.result_b, run.paired ? &*run.paired : nullptr));
  } else if (run.bootstrap) {
    fmt::print("{}", FormatCocoBootstrap(*run.bootstrap));
  }
  fmt::print(
      "{} images, {} categories, {} ground truths, {} detections; read in {:.3f} s, "
      "evaluated in {:.3f} s\n",
      r.image_ids.size(), r.category_ids.size(), r.num_gt, r.num_detections, run.read_seconds,
      r.seconds);
  if (!a.out.empty()) fmt::print("wrote {} files to {}\n", run.files.size(), a.out);
}

// `eval --shard` and `eval merge` (docs/scale.md).
void RunMerge(const EvalArgs& given, const std::vector<std::string>& shards) {
  STEREODET_CHECK(!given.out.empty()) << "eval merge: --out is required";
  STEREODET_CHECK(!shards.empty()) << "eval merge: give the shard folders";
  const EvalShardInfo first = ReadEvalShard(shards.front());
  STEREODET_CHECK(given.input.gt.empty() || given.input.gt == first.input.gt)
      << "eval merge: --gt " << given.input.gt.string() << " is not the shards' ("
      << first.input.gt.string() << "); leave it out: the merge reads the shards";
  STEREODET_CHECK(given.input.det.empty() || given.input.det == first.input.det)
      << "eval merge: --det " << given.input.det.string() << " is not the shards' ("
      << first.input.det.string() << "); leave it out: the merge reads the shards";
  EvalArgs a = given;
  a.input.gt = first.input.gt;
  a.input.det = first.input.det;
  EvaluationMergeOptions options;
  options.shards.assign(shards.begin(), shards.end());
  EvaluationOptions& e = options.evaluation;
  e.runs = OverlapSetRuns(MakeOptions(a), OverlapSets(a));
  e.input.num_threads = a.eval.num_threads;
  e.out = a.out;
  e.records = a.records;
  e.report = a.report;
  e.bootstrap = MakeBootstrapOptions(a);
  e.errors = MakeErrorOptions(a);
  e.tool_version = StereodetVersion();
  e.command_line = ProcessCommandLine();
  const EvaluationResult result = RunEvaluationMerge(options);
  PrintNotices(result.input);
  fmt::print("{}", FormatEvalTable(result.runs));
  fmt::print("merged {} shards, {} frames; evaluated in {:.3f} s\n", shards.size(),
             result.input.frames.size(), result.seconds);
  for (const EvaluationResult::RecordsFile& records : result.records) {
    fmt::print("per-detection records: {} rows in {}\n", records.rows, records.name);
  }
  fmt::print("wrote {} files to {}\n", result.files.size(), a.out);
  if (a.report) fmt::print("report: open {}\n", result.report_index.string());
}

// With --shards the frames come from the shards: --gt/--det are not given (MakeOptions asks for
// them otherwise).
EvalArgs WithShards(const EvalArgs& given, bool shards) {
  if (!shards) return given;
  STEREODET_CHECK(given.input.gt.empty() && given.input.det.empty())
      << "--shards: the frames come from the shards; leave out --gt and --det";
  EvalArgs a = given;
  a.input.gt = a.input.det = "-";
  return a;
}

void RunSweep(const EvalArgs& given, const std::string& bound, EvaluationSweepOptions options) {
  const EvalArgs a = WithShards(given, !options.shards.empty());
  options.eval = MakeSingleOptions(a);  // its filter: the fixed conditions of --where
  const auto parsed = ParseFilterBound(bound);
  STEREODET_CHECK(parsed.has_value()) << "--filter: unknown '" << bound << "' (e.g. min-area)";
  options.bound = *parsed;
  options.input = MakeInputOptions(a);
  options.out = a.out;
  const EvaluationSweepResult result = RunEvaluationSweep(options);
  // The CSV may go to stdout: the notices go to stderr then.
  PrintNotices(result.input, a.out.empty() ? stderr : stdout);
  if (a.out.empty()) {
    fmt::print("{}", result.csv);
  } else {
    fmt::print("wrote {} rows to {}\n", result.rows.size(), result.csv_path.string());
  }
  if (!result.report_index.empty()) fmt::print("report: open {}\n", result.report_index.string());
}

void RunCompare(const EvalArgs& given, EvaluationCompareOptions options) {
  const EvalArgs a = WithShards(given, !options.shards.empty());
  STEREODET_CHECK(options.shards_b.empty() || options.det_b.empty())
      << "--shards-b: B's frames come from the shards; leave out --det-b";
  options.eval = MakeSingleOptions(a);
  options.input = MakeInputOptions(a);
  options.out = a.out;
  options.bootstrap = MakeBootstrapOptions(a);
  STEREODET_CHECK(a.breakdowns.empty() || options.bootstrap)
      << "--breakdown: eval compare resamples each bin's paired A - B; give --bootstrap N too";
  const EvaluationCompareResult result = RunEvaluationCompare(options);
  PrintNotices(result.input_a);
  PrintNotices(result.input_b);
  fmt::print(
      "A = {}\nB = {}\nstereo model: dz = z^2 / (b f) * dd, b = {:.4f} m, f = {:.2f} px, dd = {} "
      "px{}\n",
      options.shards.empty() ? a.input.det.string()
                             : fmt::format("{} shards ({}, ...)", options.shards.size(),
                                           options.shards.front().string()),
      options.shards_b.empty() ? options.det_b.string()
                               : fmt::format("{} shards ({}, ...)", options.shards_b.size(),
                                             options.shards_b.front().string()),
      result.compare.baseline_m, result.compare.focal_px, result.compare.disparity_error_px,
      options.calib.empty() ? " (KITTI-like calibration)" : "");
  fmt::print("{}", FormatCompareTable(result.rows));
  if (!a.out.empty()) fmt::print("\nwrote {}\n", result.csv_path.string());
  if (result.bootstrap) {
    fmt::print("\n{}", FormatPairedBootstrapTable(*result.bootstrap));
    if (!a.out.empty()) fmt::print("wrote {}\n", result.bootstrap_csv_path.string());
    if (!result.bootstrap_samples_path.empty()) {
      fmt::print("wrote {}\n", result.bootstrap_samples_path.string());
    }
    if (!result.bootstrap_breakdown_path.empty()) {
      fmt::print("wrote {}\n", result.bootstrap_breakdown_path.string());
    }
  }
  if (!result.report_index.empty()) fmt::print("report: open {}\n", result.report_index.string());
}

}  // namespace

// `stereodet calibrate --fit DET --gt GT --split A --out FILE`: the calibrators of the detection
// folder's classes on split A (eval/calibration_fit.h), written to FILE.
void RunCalibrate(const EvalArgs& a) {
  STEREODET_CHECK(!a.out.empty()) << "--out FILE is required: the calibration file to write";
  const std::filesystem::path out = a.out;
  STEREODET_CHECK(!std::filesystem::is_directory(out))
      << "--out " << a.out << " is a folder: give the calibration file's name";
  if (std::filesystem::exists(out)) {
    // A command replaces only what it made itself: an earlier calibration file, nothing else.
    try {
      ReadScoreCalibration(out);
    } catch (const std::exception&) {
      throw std::invalid_argument("--out " + a.out +
                                  " exists and is not a calibration file: calibrate replaces only "
                                  "its own files");
    }
  }
  CalibrationFitOptions options;
  options.eval = MakeOptions(a);
  const auto method = ParseCalibrationMethod(a.method);
  STEREODET_CHECK(method.has_value())
      << "--method: unknown '" << a.method << "' (temperature, platt, isotonic)";
  options.method = *method;
  options.skip_unfittable = a.skip_unfittable;
  options.Check();
  const EvalInput input = LoadEvalFrames(MakeInputOptions(a));
  PrintNotices(input);
  CalibrationFit fit = FitScoreCalibration(input.frames, options);
  const std::vector<std::pair<std::string, std::string>> source = {
      {"gt", a.input.gt.string()},
      {"det", a.input.det.string()},
      {"split", a.input.split},
      {"input_hash", input.input_hash},
      {"tool", std::string("stereodet ") + StereodetVersion()}};
  fit.calibration.fitted_on.insert(fit.calibration.fitted_on.begin(), source.begin(), source.end());
  WriteScoreCalibration(out, fit.calibration);
  fmt::print(
      "{} calibrators on {} frames ({} {} {}, {} matcher); in-sample, over the fitted "
      "detections (TP 1, FP 0):\n",
      CalibrationMethodName(options.method), input.frames.size(),
      OverlapKindName(options.eval.metrics.front()),
      DifficultyName(options.eval.difficulties.front()), DescribeOverlaps(options.eval.classes),
      MatcherName(options.eval.matcher));
  fmt::print("{:<12} {:>7} {:>7} | {:>13} {:>13} | {}\n", "class", "TP", "FP", "Brier before",
             "after", "log loss before / after, parameters");
  size_t fitted = 0;  // into fit.calibration.classes: the fitted classes, in order
  for (const ClassCalibrationFit& c : fit.classes) {
    if (!c.fitted) {
      fmt::print("{:<12} {:>7} {:>7} | not fitted (--skip-unfittable; the file says why)\n",
                 c.class_name, c.num_tp, c.num_fp);
      continue;
    }
    const ScoreCalibrator& cal = fit.calibration.classes[fitted++].second;
    const std::string params =
        cal.method == CalibrationMethod::kIsotonic ? fmt::format("{} points", cal.x.size())
        : cal.method == CalibrationMethod::kTemperature
            ? fmt::format("T = {:.4f}", 1.0 / cal.slope)
            : fmt::format("slope {:.4f}, intercept {:.4f}", cal.slope, cal.intercept);
    fmt::print("{:<12} {:>7} {:>7} | {:>13.4f} {:>13.4f} | {:.4f} / {:.4f}, {}\n", c.class_name,
               c.num_tp, c.num_fp, c.brier_before, c.brier_after, c.nll_before, c.nll_after,
               params);
  }
  fmt::print("wrote {}; apply it with `stereodet eval --calibration {}` on another split\n", a.out,
             a.out);
}

void AddCalibrateCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  args->metrics = "2d";
  args->difficulties = "moderate";
  args->matcher = "optimal";
  CLI::App* cmd = app.add_subcommand("calibrate", CommandDescription("calibrate"));
  AddCommonOptions(cmd, args.get(), false, "--fit");
  cmd->add_option("--method", args->method,
                  "temperature | platt | isotonic (docs/metrics.md, Calibrators)")
      ->capture_default_str();
  cmd->add_option("--out", args->out, "the calibration file to write (JSON)");
  cmd->add_flag("--skip-unfittable", args->skip_unfittable,
                "a class that cannot be fitted (no true or no false positive, scores that rank "
                "false positives first) is listed in the file's \"unfitted\" (its scores then "
                "stay as they are) instead of an error");
  cmd->callback([args] { RunCalibrate(*args); });
}

void AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* eval = app.add_subcommand("eval", CommandDescription("eval"));
  AddCommonOptions(eval, args.get(), true);
  eval->add_option(
      "--out", args->out,
      "write results.json and CSVs here (one run per folder: an earlier run's folder is "
      "replaced whole; a folder of other files is refused)");
  eval->add_option("--breakdown", args->breakdowns,
                   "every figure again per bin of one property, from one matching: AXIS=EDGES, "
                   "e.g. distance=0,30,50,inf (axes: distance m, height px, occlusion, truncation, "
                   "column px; bins [a, b)); repeatable; in the table, results.json and "
                   "OUT/breakdown.csv (docs/metrics.md, Breakdowns)")
      ->allow_extra_args(false);
  eval->add_flag("--breakdown-naive", args->breakdown_naive,
                 "also each --breakdown bin evaluated on its own, its labels and detections "
                 "struck outside it before matching (the naive recomputation, for comparison: a "
                 "line under each bin in the table, results.json's breakdown[].naive). Costs about "
                 "one plain evaluation per bin (the stable bins of --breakdown cost a fraction of "
                 "one)");
  eval->add_flag("--errors", args->errors,
                 "also the TIDE-style error analysis of every cell: each false positive "
                 "classified (cls, loc, both, dupe, bkg), each miss, and the AP_R40 gained by "
                 "fixing each type alone, re-evaluated with the cell's matcher; in the table, "
                 "results.json (each cell's errors) and OUT/errors.csv (docs/metrics.md, Error "
                 "analysis). Costs about 20 plain evaluations (up to 8 re-evaluations of every "
                 "cell)");
  eval->add_option("--errors-background", args->errors_background,
                   "--errors: a false positive overlapping every label by at most this is a "
                   "background error (TIDE's 0.1)")
      ->capture_default_str();
  eval->add_flag("--records", args->records,
                 "also write OUT/matches.csv: what every detection and label counts as, per class, "
                 "metric and difficulty (docs/metrics.md)");
  eval->add_flag("--report", args->report,
                 "also write OUT/report/: index.html and figures/ as SVG and PNG, as `stereodet "
                 "report OUT` does (docs/report.md)");
  eval->add_option("--calibration", args->calibration,
                   "a score calibration file of `stereodet calibrate --fit` (fitted on another "
                   "split): every detection of a calibrated class gets its calibrated probability "
                   "before evaluating (docs/metrics.md, Calibrators)");
  eval->add_flag("--devkit-files", args->devkit_files,
                 "also write the official KITTI devkit's result files into OUT: "
                 "stats_CLASS_{detection,orientation,detection_ground,detection_3d}.txt and "
                 "plot/CLASS_*.txt, in its layout and number format (KITTI matcher; "
                 "docs/metrics.md)");
  AddBootstrapOptions(eval, args.get(),
                      "percentile intervals of every AP and Brier score in results.json and "
                      "the table (COCO mode: of the 12 numbers, over the images)");
  AddShardOption(eval, &args->input.shard)
      ->description(
          "only shard K/N (K = 0..N-1) of the frames, a contiguous range of the frame list; with "
          "--out the folder also holds what `eval merge` needs (docs/scale.md)");
  eval->add_option("--coco-gt", args->coco.gt,
                   "COCO mode: a COCO ground-truth file (instances_*.json); with --coco-det, "
                   "evaluates boxes exactly as pycocotools' COCOeval does and prints its summary "
                   "(docs/metrics.md, COCO mode)");
  eval->add_option("--coco-det", args->coco.det,
                   "COCO mode: a COCO results file, [{image_id, category_id, bbox, score}, ...]");
  eval->add_flag("--coco-honor-ignore", args->coco.eval.honor_ignore_flag,
                 "COCO mode: also ignore ground truths whose \"ignore\" is set (pycocotools "
                 "overwrites it with \"iscrowd\")");
  eval->add_option("--coco-area-ranges", args->coco_area_ranges,
                   "COCO mode: pycocotools (default: each area range matched on its own, the "
                   "boxes outside it ignored) or stable (every range counted from the one "
                   "matching of range all: a pair belongs to its ground truth's range, so no "
                   "range has an error that all has not; coco matcher only; docs/metrics.md)")
      ->default_val("pycocotools");
  eval->add_option("--coco-det-b", args->coco.det_b,
                   "COCO mode: a second results file of the same ground truth, compared with "
                   "--coco-det number by number (A - B; with --bootstrap N, paired intervals over "
                   "the images)");
  eval->add_flag("--coco-per-category", args->coco_per_category,
                 "COCO mode: also print each category's AP, AP50, AP75, APs, APm, APl and AR "
                 "(results.json has them always: categories[].stats)");
  eval->add_flag("--coco-brier", args->coco.eval.score_metrics,
                 "COCO mode: also the operating point's TP/FP/FN, Brier scores (over labels, "
                 "detections, all) and calibration per IoU threshold, category and area range: 12 "
                 "more summary lines, OUT/cells.csv and OUT/reliability.csv (--score-threshold, "
                 "--score-transform and --calibration-bins imply it)");
  eval->require_subcommand(0, 1);
  // Options of eval itself must come before a sub-subcommand; the sub-subcommands have their own.
  eval->fallthrough(false);

  auto sweep_common = std::make_shared<EvalArgs>();
  auto sweep_options = std::make_shared<EvaluationSweepOptions>();
  auto sweep_bound = std::make_shared<std::string>();
  CLI::App* sweep = eval->add_subcommand("sweep",
                                         "precision/recall of the naive and the stable filter "
                                         "along a sweep of one filter bound");
  AddCommonOptions(sweep, sweep_common.get(), false);
  sweep->add_option("--filter", *sweep_bound, "the swept bound, e.g. min-area")->required();
  sweep->add_option("--from", sweep_options->from, "the bound's first value")
      ->capture_default_str();
  sweep
      ->add_option("--to", sweep_options->to,
                   "the bound's largest value: from, from + step, ... up to this")
      ->capture_default_str();
  sweep->add_option("--step", sweep_options->step, "the bound's step, > 0")->capture_default_str();
  sweep->add_option("--where", sweep_common->filter, "fixed extra filter, e.g. max-distance=40");
  sweep->add_option("--out", sweep_common->out, "write sweep.csv here (default: stdout)");
  sweep->add_option("--shards", sweep_options->shards,
                    "read the frames from these `eval --shard K/N` folders (all N) instead of "
                    "--gt/--det: the sweep of one run (docs/scale.md)");
  sweep->add_flag("--report", sweep_options->report,
                  "also write OUT/report/: the sweep's figures and index.html (docs/report.md)");
  sweep->callback([sweep_common, sweep_options, sweep_bound] {
    RunSweep(*sweep_common, *sweep_bound, *sweep_options);
  });

  auto compare_common = std::make_shared<EvalArgs>();
  auto compare_options = std::make_shared<EvaluationCompareOptions>();
  CLI::App* compare = eval->add_subcommand("compare",
                                           "3D localization error of two detection sets "
                                           "(e.g. stereo vs LiDAR) beside the stereo model");
  AddCommonOptions(compare, compare_common.get(), true);
  compare->add_option("--det-b", compare_options->det_b, "the second detection folder");
  compare->add_option("--shards", compare_options->shards,
                      "read A's frames from these `eval --shard K/N` folders (all N) instead of "
                      "--gt/--det (docs/scale.md)");
  compare->add_option("--shards-b", compare_options->shards_b,
                      "read B's frames from these `eval --shard K/N` folders, instead of --det-b");
  compare->add_option("--calib", compare_options->calib,
                      "a KITTI calib file for b and f (default KITTI-like)");
  compare
      ->add_option("--disparity-error-px", compare_options->disparity_error_px,
                   "dd, px: the disparity error of the stereo depth-error model "
                   "dz = z^2 / (b f) x dd drawn beside the two sets")
      ->capture_default_str();
  compare->add_option("--out", compare_common->out, "write compare.csv here");
  AddBootstrapOptions(compare, compare_common.get(),
                      "paired intervals of A - B, printed and in OUT/bootstrap.csv");
  compare->add_option("--breakdown", compare_common->breakdowns,
                      "AXIS=EDGES (repeatable): with --bootstrap, every bin's paired A - B with "
                      "its interval, printed under each cell and in OUT/bootstrap_breakdown.csv "
                      "(docs/metrics.md, Breakdowns)");
  compare->add_flag(
      "--bootstrap-samples", compare_options->bootstrap_samples,
      "with --bootstrap N and --out: also OUT/bootstrap_samples.csv, every "
      "resample's A, B and A - B of AP_R40 and the three Brier scores (docs/metrics.md)");
  compare->add_flag("--report", compare_options->report,
                    "also write OUT/report/: the comparison's figures and index.html "
                    "(docs/report.md)");
  compare->callback([compare, compare_common, compare_options] {
    NoteGivenFlags(compare, compare_common.get());
    RunCompare(*compare_common, *compare_options);
  });

  auto merge_common = std::make_shared<EvalArgs>();
  auto merge_shards = std::make_shared<std::vector<std::string>>();
  CLI::App* merge = eval->add_subcommand(
      "merge",
      "combine the folders of `eval --shard K/N --out DIR` (all N) into the results folder of "
      "one run, exactly (docs/scale.md); give the shards' evaluation flags");
  AddCommonOptions(merge, merge_common.get(), true);
  merge->add_option("shards", *merge_shards, "the shard folders, in any order")->required();
  merge->add_option("--out", merge_common->out, "the merged results folder")->required();
  merge
      ->add_option("--breakdown", merge_common->breakdowns,
                   "as for eval: every figure again per bin, from the merged frames (as the "
                   "shards' other options, the shards' own)")
      ->allow_extra_args(false);
  merge->add_flag("--breakdown-naive", merge_common->breakdown_naive,
                  "as for eval: each bin also evaluated on its own, from the merged frames");
  merge->add_flag("--records", merge_common->records, "also write OUT/matches.csv");
  merge->add_flag("--report", merge_common->report, "also write OUT/report/");
  merge->add_flag("--errors", merge_common->errors,
                  "as for eval: the error analysis, of the merged frames");
  merge->add_option("--errors-background", merge_common->errors_background, "as for eval")
      ->capture_default_str();
  AddBootstrapOptions(merge, merge_common.get(), "as for eval, on the merged frames");
  merge->callback([merge, merge_common, merge_shards] {
    NoteGivenFlags(merge, merge_common.get());
    RunMerge(*merge_common, *merge_shards);
  });

  eval->callback([eval, sweep, compare, merge, args] {
    if (eval->got_subcommand(sweep) || eval->got_subcommand(compare) ||
        eval->got_subcommand(merge)) {
      return;
    }
    if (eval->count("--coco-gt") > 0 || eval->count("--coco-det") > 0) {
      NoteGivenFlags(eval, args.get());
      RunCocoEval(eval, *args);
      return;
    }
    NoteGivenFlags(eval, args.get());
    RunEval(*args);
  });
}

}  // namespace stereodet::cli
