#include "stereodet/pipelines/evaluation.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/score_calibration.h"
#include "stereodet/pipelines/evaluation_internal.h"
#include "stereodet/report/bootstrap_report.h"
#include "stereodet/report/devkit_files.h"
#include "stereodet/report/html_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/timer.h"
#include "stereodet/util/version.h"

namespace stereodet {
namespace fs = std::filesystem;

// What results.json records about the input, from what LoadEvalFrames read.
EvalRunInfo MakeRunInfo(const EvalInputOptions& options, const EvalInput& input) {
  EvalRunInfo info;
  info.gt_path = options.gt.string();
  info.det_path = options.det.string();
  info.split_path = options.split;
  info.frames_without_detections = input.frames_without_detections;
  info.lenient = options.lenient;
  info.score_if_missing = options.score_if_missing;
  info.ignored_files = input.ignored_files;
  info.skipped_lines = input.skipped_lines;
  info.input_hash = input.input_hash;
  info.det_run = input.det_run;
  info.det_not_from_run = input.det_not_from_run;
  return info;
}

std::vector<EvalOptions> OverlapSetRuns(const EvalOptions& base,
                                        const std::vector<OverlapSet>& sets) {
  std::vector<EvalOptions> runs;
  for (const OverlapSet set : sets) {
    EvalOptions run = base;
    const bool loose = set == OverlapSet::kLoose;
    for (ClassSpec& spec : run.classes) {
      spec = base.compat == EvalCompat::kOpenPcdet ? OpenPcdetClassSpec(spec.name, loose)
                                                   : KittiClassSpec(spec.name, loose);
    }
    runs.push_back(std::move(run));
  }
  return runs;
}

void EvaluationOptions::Check() const {
  input.Check();
  STEREODET_CHECK(!runs.empty()) << "no evaluation run";
  for (const EvalOptions& run : runs) {
    run.Check();
    STEREODET_CHECK(run.compat == runs.front().compat)
        << "every run must have the same compat, got " << EvalCompatName(runs.front().compat)
        << " and " << EvalCompatName(run.compat);
  }
  STEREODET_CHECK(!records || !out.empty()) << "records need an output folder (out)";
  STEREODET_CHECK(!report || !out.empty()) << "report needs an output folder (out)";
  STEREODET_CHECK(!devkit_files || !out.empty())
      << "--devkit-files needs an output folder (--out): the devkit's files go there";
  STEREODET_CHECK(!devkit_files || runs.front().matcher == Matcher::kKitti)
      << "--devkit-files: the devkit's files hold its 41 precision slots, which only the KITTI "
         "matcher computes; evaluate with --matcher kitti";
  if (bootstrap) bootstrap->Check();
  if (errors) {
    errors->Check();
    STEREODET_CHECK(runs.front().compat == EvalCompat::kDevkit)
        << "--errors: the error analysis re-evaluates with stereodet's own rules; it does not "
           "reproduce --compat openpcdet";
  }
  if (!calibration.empty()) {
    // A shard keeps its raw detection files for `eval merge`, which would evaluate them
    // uncalibrated: refused rather than merged inconsistently.
    STEREODET_CHECK(!input.shard.Recorded())
        << "--calibration with --shard: eval merge evaluates the shards' raw detections, so a "
           "sharded evaluation cannot be calibrated yet; evaluate the whole split with "
           "--calibration";
    for (const EvalOptions& run : runs) {
      STEREODET_CHECK(run.score_transform == ScoreTransform::kNone)
          << "--calibration maps the scores to probabilities: drop --score-transform "
          << ScoreTransformName(run.score_transform)
          << " (a calibration fitted on logits takes logits itself)";
    }
  }
}

EvaluationResult RunEvaluation(const EvaluationOptions& options) {
  options.Check();
  // Refuse a folder of something else before the work, not after it.
  std::optional<StagedFolder> out;
  if (!options.out.empty()) out.emplace(options.out, "eval", std::vector<std::string>{kMakerEval});
  const bool shard = options.input.shard.Recorded();
  EvalInputOptions input_options = options.input;
  input_options.keep_sources = input_options.keep_sources || (shard && out);
  EvalInput input = LoadEvalFrames(input_options);
  return EvaluateAndWrite(options, out, std::move(input),
                          [&](const fs::path& staging, const EvaluationResult& result) {
                            if (shard) WriteEvalShardFiles(staging, options.input, result.input);
                          });
}

EvaluationResult EvaluateAndWrite(
    const EvaluationOptions& options, std::optional<StagedFolder>& out, EvalInput input,
    const std::function<void(const fs::path&, const EvaluationResult&)>& before_commit) {
  EvaluationResult result;
  for (const EvalOptions& run : options.runs) {
    result.runs.push_back(EvalRun{run, {}});
    if (options.records) result.runs.back().options.keep_records = true;
  }
  result.input = std::move(input);
  result.info = MakeRunInfo(options.input, result.input);
  if (!options.calibration.empty()) {
    const ScoreCalibration calibration = ReadScoreCalibration(options.calibration);
    int64_t changed = 0;
    for (EvalFrame& frame : result.input.frames) changed += calibration.Apply(&frame.detections);
    result.info.calibration_path = options.calibration.string();
    result.info.calibrated_detections = changed;
  }
  result.info.tool_version = options.tool_version;
  result.info.command_line = options.command_line;
  for (EvalRun& run : result.runs) {
    run.result = Evaluate(result.input.frames, run.options);
    result.seconds += run.result.seconds;
    if (options.bootstrap) {
      BootstrapOptions bootstrap = *options.bootstrap;
      bootstrap.num_threads = options.input.num_threads;
      run.bootstrap = Bootstrap(result.input.frames, run.options, bootstrap);
      result.bootstrap_seconds += run.bootstrap->seconds;
    }
    if (options.errors) {
      const Timer timer;
      run.errors = AnalyzeAllErrors(result.input.frames, run.options, *options.errors);
      result.errors_seconds += timer.ElapsedSeconds();
    }
  }
  if (!out) return result;

  const fs::path& staging = out->path();
  for (const fs::path& path : WriteEvalReport(staging, result.runs, result.info)) {
    result.files.push_back(options.out / path.lexically_relative(staging));
  }
  if (options.records) {
    for (const EvalRun& run : result.runs) {
      // One file per overlap set when there are several, named as the curve files are.
      const std::string name =
          result.runs.size() == 1
              ? std::string("matches.csv")
              : fmt::format("matches_{}.csv", DescribeOverlaps(run.options.classes));
      const int64_t rows = WriteMatchRecordsCsv(staging / name, run.result, result.input.frames);
      result.files.push_back(options.out / name);
      result.records.push_back({name, rows});
    }
  }
  if (options.devkit_files) {
    for (const fs::path& path : WriteDevkitFiles(staging, result.runs.front().result)) {
      result.files.push_back(options.out / path.lexically_relative(staging));
    }
  }
  if (options.report) {
    std::vector<ReportSource> sources = {ReadReportSource(staging, FolderLabel(options.out))};
    sources.front().folder = options.out;  // where it will be, not the staging folder
    const ReportResult report = WriteReportFiles(staging / "report", sources, options.report_png,
                                                 ReportOptions().png_scale);
    for (const fs::path& path : report.files) {
      result.files.push_back(options.out / path.lexically_relative(staging));
    }
    result.report_index = options.out / "report" / "index.html";
    result.report_notes = report.notes;
  }
  if (before_commit) before_commit(staging, result);
  out->Commit();
  return result;
}

namespace {

// EvalInputOptions::Check, but without --gt/--det when the frames come from shards.
void CheckInput(const EvalInputOptions& input, bool from_shards) {
  EvalInputOptions checked = input;
  if (from_shards) checked.gt = checked.det = "-";
  checked.Check();
}

}  // namespace

void EvaluationSweepOptions::Check() const {
  CheckInput(input, !shards.empty());
  eval.Check();  // the sweep's range is FilterSweep's to check
  STEREODET_CHECK(!report || !out.empty()) << "sweep: report needs an output folder (out)";
}

namespace {

struct CsvOutput {
  std::filesystem::path csv_path;      // empty without an output folder
  std::filesystem::path report_index;  // empty without a report
};

// The sweep's and the compare's outputs: OUT/NAME (atomically) when there is an output folder,
// then, if asked, the report of that folder.
CsvOutput WriteCsvAndReport(const std::filesystem::path& out, const char* name,
                            const std::string& csv, bool report) {
  CsvOutput written;
  if (!out.empty()) {
    written.csv_path = out / name;
    WriteFileAtomically(written.csv_path, csv);
  }
  if (report) {
    ReportOptions report_options;
    report_options.results = {out};
    written.report_index = WriteReport(report_options).index;
  }
  return written;
}

}  // namespace

EvaluationSweepResult RunEvaluationSweep(const EvaluationSweepOptions& options) {
  options.Check();
  if (!options.out.empty()) CheckOutputFolderOwner(options.out, "eval sweep", {kMakerSweep});
  EvaluationSweepResult result;
  result.input = options.shards.empty() ? LoadEvalFrames(options.input)
                                        : LoadEvalShards(options.shards, options.input.num_threads);
  result.rows = FilterSweep(result.input.frames, options.eval, options.bound, options.from,
                            options.to, options.step);
  result.csv = FormatSweepCsv(result.rows, options.bound);
  const CsvOutput written = WriteCsvAndReport(options.out, "sweep.csv", result.csv, options.report);
  result.csv_path = written.csv_path;
  result.report_index = written.report_index;
  return result;
}

void EvaluationCompareOptions::Check() const {
  STEREODET_CHECK(shards.empty() == shards_b.empty())
      << "compare: give the shards of both detection sets (shards and shards_b), or neither";
  CheckInput(input, !shards.empty());
  STEREODET_CHECK(!det_b.empty() || !shards_b.empty())
      << "compare: no second detection folder (det_b)";
  eval.Check();
  STEREODET_CHECK(!report || !out.empty()) << "compare: report needs an output folder (out)";
  if (bootstrap) bootstrap->Check();
  STEREODET_CHECK(!bootstrap_samples || (bootstrap && !out.empty()))
      << "compare: bootstrap_samples needs a bootstrap and an output folder (out)";
}

EvaluationCompareResult RunEvaluationCompare(const EvaluationCompareOptions& options) {
  options.Check();
  if (!options.out.empty()) CheckOutputFolderOwner(options.out, "eval compare", {kMakerCompare});
  EvaluationCompareResult result;
  // What A and B were, for compare.json (the report's legends name them).
  EvalInputOptions a = options.input, b = options.input;
  b.det = options.det_b;
  if (options.shards.empty()) {
    result.input_a = LoadEvalFrames(options.input);
    EvalInputOptions input_b = options.input;
    input_b.det = options.det_b;
    result.input_b = LoadEvalFrames(input_b);
  } else {
    result.input_a = LoadEvalShards(options.shards, options.input.num_threads, &a);
    result.input_b = LoadEvalShards(options.shards_b, options.input.num_threads, &b);
    STEREODET_CHECK(a.gt == b.gt && a.split == b.split && a.lenient == b.lenient &&
                    a.score_if_missing == b.score_if_missing)
        << "compare: the shards of A read other labels (--gt " << a.gt.string() << " --split '"
        << a.split << "') than those of B (--gt " << b.gt.string() << " --split '" << b.split
        << "')";
  }
  result.result_a = Evaluate(result.input_a.frames, options.eval);
  result.result_b = Evaluate(result.input_b.frames, options.eval);
  const Calibration calib =
      options.calib.empty() ? KittiLikeCalibration() : ReadCalibration(options.calib);
  result.compare.baseline_m = calib.BaselineM();
  result.compare.focal_px = calib.FocalPx();
  result.compare.disparity_error_px = options.disparity_error_px;
  result.rows = CompareLocalization(result.result_a, result.result_b, result.compare);
  result.csv = FormatCompareCsv(result.rows);
  if (!options.out.empty()) {
    const nlohmann::json inputs = {{"tool", "eval compare"},  {"version", StereodetVersion()},
                                   {"gt", a.gt.string()},     {"split", a.split},
                                   {"det_a", a.det.string()}, {"det_b", b.det.string()}};
    WriteFileAtomically(options.out / "compare.json", inputs.dump(2) + "\n");
  }
  const CsvOutput written =
      WriteCsvAndReport(options.out, "compare.csv", result.csv, options.report);
  result.csv_path = written.csv_path;
  result.report_index = written.report_index;
  if (options.bootstrap) {
    BootstrapOptions bootstrap = *options.bootstrap;
    bootstrap.num_threads = options.input.num_threads;
    bootstrap.keep_samples = bootstrap.keep_samples || options.bootstrap_samples;
    result.bootstrap =
        PairedBootstrap(result.input_a.frames, result.input_b.frames, options.eval, bootstrap);
    result.bootstrap_csv = FormatPairedBootstrapCsv(*result.bootstrap);
    if (!options.out.empty()) {
      result.bootstrap_csv_path = options.out / "bootstrap.csv";
      WriteFileAtomically(result.bootstrap_csv_path, result.bootstrap_csv);
    }
    if (!options.eval.breakdowns.empty() && !options.out.empty()) {
      result.bootstrap_breakdown_path = options.out / "bootstrap_breakdown.csv";
      WriteFileAtomically(result.bootstrap_breakdown_path,
                          FormatPairedBootstrapBreakdownCsv(*result.bootstrap));
    }
    if (options.bootstrap_samples) {
      result.bootstrap_samples_path = options.out / "bootstrap_samples.csv";
      WriteFileAtomically(result.bootstrap_samples_path,
                          FormatPairedBootstrapSamplesCsv(*result.bootstrap));
    }
  }
  return result;
}

}  // namespace stereodet
