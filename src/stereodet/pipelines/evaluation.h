// The evaluation commands as library calls: "evaluate these folders with these options and write
// this results folder" is one call. `stereodet eval` is RunEvaluation, `eval sweep`
// RunEvaluationSweep, `eval compare` RunEvaluationCompare; the CLI binds its flags to the options
// and prints the results, and the Python module can call the same.
//
//   EvaluationOptions options;
//   options.input.gt = "kitti";  options.input.det = "results/data";  options.input.split = "val";
//   options.out = "eval";  // results.json, summary.csv, curves/
//   const EvaluationResult result = RunEvaluation(options);
//   std::cout << FormatEvalTable(result.runs);
#ifndef STEREODET_PIPELINES_EVALUATION_H_
#define STEREODET_PIPELINES_EVALUATION_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/compare.h"
#include "stereodet/eval/eval_input.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/report/eval_report.h"

namespace stereodet {

// The options of one evaluation per overlap set in `sets`, in that order: `base` with its classes
// replaced by KITTI's specs (OpenPCDet's with compat kOpenPcdet) of the same names for that set
// (KittiClassSpec, OpenPcdetClassSpec). Custom thresholds of `base` are not kept.
std::vector<EvalOptions> OverlapSetRuns(const EvalOptions& base,
                                        const std::vector<OverlapSet>& sets);

struct EvaluationOptions {
  EvalInputOptions input;  // the label and detection folders, the split, lenient reading
  // One evaluation of the frames per entry, e.g. one per overlap set (OverlapSetRuns). Every entry
  // has the same compat. Default: one run with EvalOptions' defaults.
  std::vector<EvalOptions> runs = {EvalOptions()};
  // The results folder, one run per folder (a StagedFolder: only an earlier eval output, with its
  // results.json, is replaced): results.json, summary.csv and curves/ (WriteEvalReport). A folder
  // of other files is refused before anything is read. Empty: nothing is written.
  std::filesystem::path out;
  // Also write the per-detection records (WriteMatchRecordsCsv) as OUT/matches.csv, or with several
  // runs OUT/matches_OVERLAPS.csv (DescribeOverlaps) per run; sets every run's keep_records.
  // Requires out.
  bool records = false;
  // Also write OUT/report/: index.html and figures/ (WriteReportFiles on the results.json just
  // written, as `stereodet report OUT` would). Requires out.
  bool report = false;
  bool report_png = true;  // the report's PNG figures too (where the build has librsvg)
  // Also write the official devkit's result files into OUT (WriteDevkitFiles: stats_*.txt and
  // plot/*.txt) from the first run (the strict overlap set). Requires out and the KITTI matcher.
  bool devkit_files = false;
  // Bootstrap intervals over frames for every run (Bootstrap; EvalRun::bootstrap), in
  // results.json and the table. Unset: none. Its num_threads is replaced by input.num_threads.
  std::optional<BootstrapOptions> bootstrap;
  // The TIDE-style error analysis of every run's cells (AnalyzeAllErrors; EvalRun::errors), in
  // results.json, OUT/errors.csv and the table. Unset: none. Not with compat openpcdet.
  std::optional<ErrorAnalysisOptions> errors;
  // A score calibration file (kitti/score_calibration.h, `stereodet calibrate --fit`): applied to
  // the detections once read, before every run; recorded in results.json ("input.calibration").
  // Its outputs are probabilities: every run's score_transform must be kNone (a calibration fitted
  // on logits says so itself). Not with input.shard (eval merge reads the raw files). Empty: none.
  std::filesystem::path calibration;
  // Provenance recorded in results.json (EvalRunInfo).
  std::string tool_version;
  std::string command_line;

  // Throws std::invalid_argument for no runs, runs of different compat, records without out, or
  // report without out, or a bad input or run setting (EvalInputOptions::Check,
  // EvalOptions::Check).
  void Check() const;
};

struct EvaluationResult {
  EvalInput input;  // the frames read, and what was ignored or skipped (EvalInput::Notices)
  // The runs' options as evaluated (keep_records set with records) and their results, in the order
  // of EvaluationOptions::runs.
  std::vector<EvalRun> runs;
  EvalRunInfo info;              // what results.json records about the input and the run
  double seconds = 0;            // the runs' Evaluate() time, summed
  double bootstrap_seconds = 0;  // the runs' Bootstrap() time, summed (0 without bootstrap)
  double errors_seconds = 0;     // the runs' AnalyzeAllErrors() time, summed (0 without errors)
  // With out: every file written, as paths under out (the report's, then the records files).
  std::vector<std::filesystem::path> files;
  // With records: per run, the records file's name under out and its rows.
  struct RecordsFile {
    std::string name;
    int64_t rows = 0;
  };
  std::vector<RecordsFile> records;
  // With report: OUT/report/index.html, and notes of the report (e.g. PNG files not written).
  std::filesystem::path report_index;
  std::vector<std::string> report_notes;
};

// Checks the options, claims `out` (refusing a folder of other files), reads the frames
// (LoadEvalFrames), evaluates every run and writes the results folder, which replaces `out` whole
// at the end (nothing is left there if a step throws). Throws what those steps throw:
// std::invalid_argument for bad options, std::runtime_error or ParseError for bad inputs or a
// failed write.
//
// With options.input.shard (util/shard.h) it evaluates only that shard's frames, and the results
// folder also holds what `eval merge` needs (RunEvaluationMerge): OUT/eval_shard.json (the shard,
// its input options and the folder-level facts LoadEvalFrames found) and OUT/eval_frames.dat (the
// bytes of the shard's label and detection files).
EvaluationResult RunEvaluation(const EvaluationOptions& options);

// `stereodet eval merge`: N shard folders of one evaluation -> the results folder of one run.
//
// The merge is exact by construction, for every matcher and every metric: it concatenates the
// shards' frame bytes (eval_frames.dat) in shard order, which is the whole frame list in order,
// parses them with LoadEvalFrames' own code (EvalInputFromSources) and evaluates them once, as
// one process would; results.json, summary.csv, curves/, matches.csv and the report are those of
// `stereodet eval` on the whole list, with the same input_hash, except for the provenance
// (command_line, tool version, seconds). See docs/scale.md for what it costs.
struct EvaluationMergeOptions {
  // Folders written by RunEvaluation with input.shard, in any order: shards 0..N-1 of one N,
  // each once, of the same input (gt, det, split, lenient).
  std::vector<std::filesystem::path> shards;
  // runs, out, records, report and provenance as for RunEvaluation. `input` is the shards' (its
  // gt, det, split and lenient are filled from them; input.num_threads is used). Every run's
  // options must be those the shards were evaluated with (results.json's "options" and
  // "overlap_sets", num_threads aside): a merge with other options is refused.
  EvaluationOptions evaluation;

  // Throws std::invalid_argument for no shards, no evaluation.out or bad evaluation options
  // (input aside).
  void Check() const;
};

// What a shard folder says about itself (OUT/eval_shard.json).
struct EvalShardInfo {
  Shard shard;
  int64_t frames = 0;       // frames of the shard
  std::string frames_hash;  // FNV-1a 64 of its eval_frames.dat, 16 hex digits
  EvalInputOptions input;   // gt, det, split, lenient as the shard read them
};

// Reads DIR/eval_shard.json. Throws std::runtime_error naming the folder when it is not a shard
// folder (no eval_shard.json), ParseError for a malformed one.
EvalShardInfo ReadEvalShard(const std::filesystem::path& dir);

// The frames of the folders of `eval --shard K/N` (all N of one input, in any order), as
// LoadEvalFrames reads the whole list: the shards' label and detection bytes in shard order,
// parsed as LoadEvalFrames parses them (on num_threads threads). With `shards_input`, the input
// the shards read (gt, det, split, lenient) goes there. Throws std::invalid_argument for a shard
// missing, given twice, of another N or another input, std::runtime_error for a folder that is
// not a shard and for bad frame files. What `eval merge`, and `eval sweep|compare --shards`, read.
EvalInput LoadEvalShards(const std::vector<std::filesystem::path>& shards, int num_threads,
                         EvalInputOptions* shards_input = nullptr);

// Checks the shards (all of 0..N-1 once, one input), claims `out`, reads the shards' frames,
// evaluates and writes as RunEvaluation does; refuses before the commit, naming the shard, when
// its options differ. Throws std::invalid_argument for a bad set of shards or options,
// std::runtime_error / ParseError for unreadable shard files.
EvaluationResult RunEvaluationMerge(const EvaluationMergeOptions& options);

// `stereodet eval sweep`: precision and recall of the naive and the stable filter along a sweep of
// one filter bound (FilterSweep).
struct EvaluationSweepOptions {
  EvalInputOptions input;
  // Non-empty: the frames are those of these `eval --shard` folders (LoadEvalShards; input.gt and
  // det are not read, input.num_threads is used), which gives the rows of the sweep of one run.
  std::vector<std::filesystem::path> shards;
  // One run; its filter's conditions are the fixed ones the swept bound is added to.
  EvalOptions eval;
  FilterBound bound = FilterBound::kMinArea;  // the swept bound
  double from = 0, to = 200, step = 5;        // its values: from, from + step, ... <= to
  // Where OUT/sweep.csv goes (written atomically; the folder is created). Empty: not written.
  std::filesystem::path out;
  // Also write OUT/report/ (WriteReport on OUT: the sweep figures, SVG and PNG). Requires out.
  bool report = false;
  // Throws std::invalid_argument for a bad input or eval setting (FilterSweep checks the range).
  void Check() const;
};

struct EvaluationSweepResult {
  EvalInput input;
  std::vector<SweepRow> rows;
  std::string csv;                     // FormatSweepCsv(rows, bound)
  std::filesystem::path csv_path;      // OUT/sweep.csv; empty without out
  std::filesystem::path report_index;  // with report: OUT/report/index.html
};

EvaluationSweepResult RunEvaluationSweep(const EvaluationSweepOptions& options);

// `stereodet eval compare`: the 3D localization error of two detection sets of the same frames
// beside the stereo depth-error model (CompareLocalization).
struct EvaluationCompareOptions {
  EvalInputOptions input;       // input.det holds the detections A
  std::filesystem::path det_b;  // the detections B, read like A (same labels, split, leniency)
  // Both non-empty: A's and B's frames are those of these `eval --shard` folders (LoadEvalShards;
  // input.gt, det and det_b are not read), shards of the same labels, split and leniency.
  std::vector<std::filesystem::path> shards, shards_b;
  EvalOptions eval;  // both are evaluated with these
  // A KITTI calib file whose baseline and focal length the model uses. Empty: KittiLikeCalibration.
  std::filesystem::path calib;
  // The model's disparity error (the baseline and focal length are set from `calib`).
  double disparity_error_px = 1.0;
  // Where OUT/compare.csv goes (written atomically). Empty: not written.
  std::filesystem::path out;
  // Also write OUT/report/ (WriteReport on OUT: the compare figures, SVG and PNG). Requires out.
  bool report = false;
  // A paired bootstrap of A and B over the same resampled frames (PairedBootstrap): the interval
  // of each metric's A - B, in OUT/bootstrap.csv (FormatPairedBootstrapCsv). Unset: none. Its
  // num_threads is replaced by input.num_threads.
  std::optional<BootstrapOptions> bootstrap;
  // With bootstrap and out: also OUT/bootstrap_samples.csv, every resample's A, B and A - B of
  // AP_R40 and Brier over labels in every evaluated cell (FormatPairedBootstrapSamplesCsv): what a
  // rule over several seed pairs averages resample by resample (docs/experiment.md).
  bool bootstrap_samples = false;
  void Check() const;  // throws std::invalid_argument
};

struct EvaluationCompareResult {
  EvalInput input_a, input_b;
  EvalResult result_a, result_b;
  CompareOptions compare;  // as used: baseline_m and focal_px from the calibration
  std::vector<CompareRow> rows;
  std::string csv;                     // FormatCompareCsv(rows)
  std::filesystem::path csv_path;      // OUT/compare.csv; empty without out
  std::filesystem::path report_index;  // with report: OUT/report/index.html
  // With bootstrap: the paired intervals, their CSV and OUT/bootstrap.csv (empty without out).
  std::optional<PairedBootstrapResult> bootstrap;
  std::string bootstrap_csv;
  std::filesystem::path bootstrap_csv_path;
  std::filesystem::path bootstrap_samples_path;  // with bootstrap_samples and out
  // With eval.breakdowns and out: every bin's paired A - B (FormatPairedBootstrapBreakdownCsv).
  std::filesystem::path bootstrap_breakdown_path;
};

// Reads A then B, evaluates both, then reads the calibration and compares.
EvaluationCompareResult RunEvaluationCompare(const EvaluationCompareOptions& options);

}  // namespace stereodet

#endif  // STEREODET_PIPELINES_EVALUATION_H_
