// stereodet._core's evaluation: options, frames from annotation dicts or folders, Evaluate(), the
// result object (attributes, the CLI's results.json as a dict, flat rows, per-detection records
// as numpy arrays), OpenPCDet's get_official_eval_result, the filter sweep and compare. Folders go
// through the library's evaluation calls (pipelines/evaluation.h: RunEvaluation,
// RunEvaluationSweep, RunEvaluationCompare), so that a results folder is the CLI's.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "annos.h"
#include "common.h"
#include "stereodet/eval/bootstrap.h"
#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/compare.h"
#include "stereodet/eval/error_analysis.h"
#include "stereodet/eval/eval_input.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/filter.h"
#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/pipelines/evaluation.h"
#include "stereodet/report/error_report.h"
#include "stereodet/report/eval_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/version.h"

namespace stereodet::python {

namespace {

namespace fs = std::filesystem;

using Frames = std::shared_ptr<const std::vector<EvalFrame>>;

using Runs = std::shared_ptr<const std::vector<EvalRun>>;

// An evaluation as Python holds it: its runs (one per overlap set), and what they were computed
// from (the records refer to the frames; to_dict() writes the options and the inputs, as
// results.json does). EvalResult.runs[i] shares the runs and selects one.
struct PyEvalResult {
  Runs runs;
  int index = -1;  // -1: every run; else the run `index` alone
  EvalRunInfo info;
  Frames frames;
  std::vector<fs::path> files;  // what RunEvaluation / WriteReport wrote; empty without out

  std::span<const EvalRun> Selected() const {
    if (index < 0) return {runs->data(), runs->size()};
    return {runs->data() + index, 1};
  }
  const EvalRun& First() const { return Selected().front(); }
  bool Several() const { return Selected().size() > 1; }
};

PyEvalResult MakeResult(std::vector<EvalRun> runs, EvalRunInfo info, Frames frames) {
  PyEvalResult out;
  out.runs = std::make_shared<const std::vector<EvalRun>>(std::move(runs));
  out.info = std::move(info);
  out.frames = std::move(frames);
  return out;
}

// A frame set: converted once, evaluated any number of times.
struct PyFrames {
  Frames frames;
  EvalRunInfo info;  // what LoadEvalFrames read (folders); empty for annotation dicts
  std::vector<std::string> notices;
};

// --- Names ---

Difficulty ParseDifficulty(py::handle value) {
  if (py::isinstance<py::int_>(value)) {
    const int d = value.cast<int>();
    if (d >= 0 && d < kNumDifficulties) return static_cast<Difficulty>(d);
  } else if (py::isinstance<py::str>(value)) {
    const std::string text = value.cast<std::string>();
    for (int d = 0; d < kNumDifficulties; ++d) {
      if (EqualsIgnoreCase(text, DifficultyName(static_cast<Difficulty>(d)))) {
        return static_cast<Difficulty>(d);
      }
    }
  }
  ThrowValueError("difficulty: unknown " + py::repr(value).cast<std::string>() +
                  " (easy, moderate, hard, or 0, 1, 2)");
}

OverlapKind ParseKind(const std::string& text) {
  std::string lower = text;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ParseChoice([](const std::string& s) { return ParseOverlapKind(s); }, lower, "metric",
                     "2d, bev, 3d");
}

FilterBound ParseBound(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return ParseChoice([](const std::string& s) { return ParseFilterBound(s); }, name, "filter",
                     "min-height, max-height, min-width, max-width, min-area, max-area, "
                     "min-distance, max-distance, max-occlusion, max-truncation, difficulty");
}

// A filter: the CLI's text ("min-area=100,max-distance=40"), a dict {"min_area": 100, ...}
// (underscores or hyphens; difficulty as a name or 0..2), a list of (bound, value) pairs, or None.
std::vector<FilterCondition> ParseConditions(py::handle value) {
  std::vector<FilterCondition> out;
  if (value.is_none()) return out;
  if (py::isinstance<py::str>(value)) return ParseFilterConditions(value.cast<std::string>());
  py::object items = py::reinterpret_borrow<py::object>(value);
  if (py::isinstance<py::dict>(value)) items = value.attr("items")();
  for (py::handle item : items) {
    py::tuple pair = py::reinterpret_borrow<py::object>(item).cast<py::tuple>();
    if (pair.size() != 2) ThrowValueError("filters: expected (bound, value) pairs");
    FilterCondition c;
    c.bound = ParseBound(pair[0].cast<std::string>());
    if (c.bound == FilterBound::kDifficulty) {
      c.value = static_cast<double>(ParseDifficulty(pair[1]));
    } else {
      c.value = pair[1].cast<double>();
    }
    out.push_back(c);
  }
  return out;
}

std::string ConditionsText(const std::vector<FilterCondition>& conditions) {
  std::string out;
  for (const FilterCondition& c : conditions) {
    if (!out.empty()) out += ",";
    out += std::string(FilterBoundName(c.bound)) + "=" +
           py::str(py::float_(c.value)).cast<std::string>();
  }
  return out;
}

// --- Frames ---

std::string FrameId(py::handle det_annos, py::ssize_t i) {
  if (PyMapping_Check(det_annos.ptr()) && py::hasattr(det_annos, "keys") &&
      PySequence_Contains(det_annos.ptr(), py::str("frame_id").ptr()) == 1) {
    return py::str(det_annos["frame_id"]).cast<std::string>();
  }
  std::string id = std::to_string(i);
  return std::string(id.size() < 6 ? 6 - id.size() : 0, '0') + id;
}

PyFrames FramesFromAnnos(py::handle gt_annos, py::handle dt_annos) {
  if (!py::isinstance<py::sequence>(gt_annos) || py::isinstance<py::str>(gt_annos)) {
    ThrowValueError("gt_annos: expected a list of annotation dicts, got " + Describe(gt_annos));
  }
  if (!py::isinstance<py::sequence>(dt_annos) || py::isinstance<py::str>(dt_annos)) {
    ThrowValueError("dt_annos: expected a list of annotation dicts, got " + Describe(dt_annos));
  }
  const py::sequence gt = py::reinterpret_borrow<py::sequence>(gt_annos);
  const py::sequence dt = py::reinterpret_borrow<py::sequence>(dt_annos);
  if (gt.size() != dt.size()) {
    ThrowValueError("gt_annos and dt_annos differ in length: " + std::to_string(gt.size()) +
                    " vs " + std::to_string(dt.size()) + " frames");
  }
  auto frames = std::make_shared<std::vector<EvalFrame>>(gt.size());
  for (size_t i = 0; i < gt.size(); ++i) {
    const py::object g = gt[i], d = dt[i];
    EvalFrame& f = (*frames)[i];
    f.id = FrameId(d, static_cast<py::ssize_t>(i));
    f.labels = ObjectsFromAnnos(g, false, "gt_annos[" + std::to_string(i) + "]");
    f.detections = ObjectsFromAnnos(d, true, "dt_annos[" + std::to_string(i) + "]");
  }
  PyFrames out;
  out.frames = std::move(frames);
  out.info.tool_version = StereodetVersion();
  return out;
}

EvalInputOptions InputOptions(const fs::path& gt, const fs::path& det, const std::string& split,
                              bool lenient, int num_threads, bool missing_as_empty,
                              std::optional<double> score_if_missing = std::nullopt) {
  EvalInputOptions input;
  input.score_if_missing = score_if_missing;
  input.gt = gt;
  input.det = det;
  input.split = split;
  input.lenient = lenient;
  input.missing_as_empty = missing_as_empty;
  input.num_threads = num_threads;
  return input;
}

PyFrames FramesFromFolders(const std::string& gt, const std::string& det, const std::string& split,
                           bool lenient, int num_threads, bool missing_as_empty,
                           std::optional<double> score_if_missing) {
  const EvalInputOptions options =
      InputOptions(gt, det, split, lenient, num_threads, missing_as_empty, score_if_missing);
  EvalInput input;
  {
    ReleaseGil release;
    input = LoadEvalFrames(options);
  }
  PyFrames out;
  out.notices = input.Notices();
  out.info.tool_version = StereodetVersion();
  out.info.gt_path = gt;
  out.info.det_path = det;
  out.info.split_path = split;
  out.info.frames_without_detections = std::move(input.frames_without_detections);
  out.info.lenient = lenient;
  out.info.ignored_files = std::move(input.ignored_files);
  out.info.skipped_lines = std::move(input.skipped_lines);
  out.info.input_hash = input.input_hash;
  out.frames = std::make_shared<const std::vector<EvalFrame>>(std::move(input.frames));
  return out;
}

// Every run on the frames, in order (the in-memory path of annotation dicts).
// evaluate()'s bootstrap=N (0: none), bootstrap_seed, bootstrap_confidence as the CLI's --bootstrap
// flags: checked as the CLI checks them.
std::optional<BootstrapOptions> BootstrapOf(int resamples, uint64_t seed, double confidence,
                                            const std::string& method, int num_threads) {
  if (resamples == 0) return std::nullopt;
  if (resamples < 1 || resamples > kMaxBootstrapResamples) {
    ThrowValueError("bootstrap: resamples must be in [1, " +
                    std::to_string(kMaxBootstrapResamples) + "], got " + std::to_string(resamples));
  }
  if (!(confidence > 0 && confidence < 1)) {
    ThrowValueError("bootstrap_confidence: must be in (0, 1), got " + std::to_string(confidence));
  }
  const std::optional<BootstrapMethod> parsed = ParseBootstrapMethod(method);
  if (!parsed) ThrowValueError("bootstrap_method: 'percentile' or 'bca', got '" + method + "'");
  BootstrapOptions b;
  b.method = *parsed;
  b.num_resamples = resamples;
  b.seed = seed;
  b.confidence = confidence;
  b.num_threads = num_threads;
  return b;
}

PyEvalResult EvaluateFrames(const PyFrames& frames, const std::vector<EvalOptions>& options,
                            int bootstrap = 0, uint64_t bootstrap_seed = 1,
                            double bootstrap_confidence = 0.95,
                            const std::string& bootstrap_method = "percentile") {
  std::vector<EvalRun> runs;
  const std::optional<BootstrapOptions> b =
      BootstrapOf(bootstrap, bootstrap_seed, bootstrap_confidence, bootstrap_method,
                  options.empty() ? 0 : options.front().num_threads);
  {
    ReleaseGil release;
    if (options.empty()) throw std::invalid_argument("no evaluation run");
    for (const EvalOptions& o : options) {
      o.Check();
      runs.push_back(EvalRun{o, Evaluate(*frames.frames, o)});
      // As RunEvaluation does it: the same frames and options, resampled.
      if (b) runs.back().bootstrap = Bootstrap(*frames.frames, o, *b);
    }
  }
  return MakeResult(std::move(runs), frames.info, frames.frames);
}

// The runs of one set of options per overlap set (OverlapSetRuns), from their names.
std::vector<EvalOptions> OverlapRuns(const EvalOptions& base,
                                     const std::vector<std::string>& names) {
  std::vector<OverlapSet> sets;
  for (const std::string& name : names) {
    const OverlapSet set = ParseChoice([](const std::string& t) { return ParseOverlapSet(t); },
                                       name, "overlaps", "strict, loose");
    if (std::find(sets.begin(), sets.end(), set) != sets.end()) {
      ThrowValueError("overlaps: '" + name + "' given twice");
    }
    sets.push_back(set);
  }
  if (sets.empty()) ThrowValueError("overlaps: no overlap set (strict, loose)");
  return OverlapSetRuns(base, sets);
}

// `stereodet eval` on folders: RunEvaluation, which with `out` writes the CLI's results folder
// (and with `records` its matches*.csv). Records without out are kept in memory only.
PyEvalResult RunFolders(const fs::path& gt, const fs::path& det, const std::string& split,
                        bool lenient, int num_threads, std::vector<EvalOptions> runs,
                        const fs::path& out, bool records, bool missing_as_empty,
                        std::optional<double> score_if_missing, int bootstrap,
                        uint64_t bootstrap_seed, double bootstrap_confidence,
                        const std::string& bootstrap_method) {
  EvaluationOptions options;
  options.bootstrap =
      BootstrapOf(bootstrap, bootstrap_seed, bootstrap_confidence, bootstrap_method, num_threads);
  options.input =
      InputOptions(gt, det, split, lenient, num_threads, missing_as_empty, score_if_missing);
  if (records && out.empty()) {
    for (EvalOptions& run : runs) run.keep_records = true;
  }
  options.runs = std::move(runs);
  options.out = out;
  options.records = records && !out.empty();
  options.tool_version = StereodetVersion();
  EvaluationResult result;
  {
    ReleaseGil release;
    result = RunEvaluation(options);
  }
  PyEvalResult py_result =
      MakeResult(std::move(result.runs), std::move(result.info),
                 std::make_shared<const std::vector<EvalFrame>>(std::move(result.input.frames)));
  py_result.files = std::move(result.files);
  return py_result;
}

// The results folder of an in-memory evaluation, as RunEvaluation writes it: the report
// (WriteEvalReport) and with `records` matches.csv (matches_OVERLAPS.csv per run with several),
// staged and replacing `out` whole.
void WriteReport(PyEvalResult& r, const fs::path& out, bool records) {
  const std::span<const EvalRun> selected = r.Selected();
  if (records) {
    for (const EvalRun& run : selected) {
      if (!run.options.keep_records) {
        ThrowValueError("out with records: evaluate with records=True");
      }
    }
  }
  ReleaseGil release;
  StagedFolder folder(out, "eval", {kMakerEval});
  // Every run as evaluated (what evaluate() writes), or a copy of the one selected.
  std::vector<EvalRun> one;
  if (r.index >= 0) one.assign(selected.begin(), selected.end());
  const std::vector<EvalRun>& runs = r.index < 0 ? *r.runs : one;
  std::vector<fs::path> files;
  for (const fs::path& path : WriteEvalReport(folder.path(), runs, r.info)) {
    files.push_back(out / path.lexically_relative(folder.path()));
  }
  if (records) {
    for (const EvalRun& run : runs) {
      const std::string name = runs.size() == 1
                                   ? std::string("matches.csv")
                                   : "matches_" + DescribeOverlaps(run.options.classes) + ".csv";
      WriteMatchRecordsCsv(folder.path() / name, run.result, *r.frames);
      files.push_back(out / name);
    }
  }
  folder.Commit();
  r.files = std::move(files);
}

// --- Results to Python ---

py::dict OperatingPointDict(const OperatingPoint& p) {
  py::dict d;
  d["threshold"] = p.threshold;
  d["tp"] = p.tp;
  d["fp"] = p.fp;
  d["fn"] = p.fn;
  d["precision"] = p.precision;
  d["recall"] = p.recall;
  d["f1"] = p.f1;
  return d;
}

py::dict CurveDict(const std::vector<CurvePoint>& curve) {
  const auto n = static_cast<py::ssize_t>(curve.size());
  py::array_t<double> threshold(n), precision(n), recall(n), similarity(n), orientation(n);
  py::array_t<int64_t> tp(n), fp(n), fn(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const CurvePoint& p = curve[i];
    threshold.mutable_data()[i] = p.threshold;
    tp.mutable_data()[i] = p.tp;
    fp.mutable_data()[i] = p.fp;
    fn.mutable_data()[i] = p.fn;
    precision.mutable_data()[i] = p.precision;
    recall.mutable_data()[i] = p.recall;
    similarity.mutable_data()[i] = p.similarity;
    orientation.mutable_data()[i] = p.orientation;
  }
  py::dict d;
  d["threshold"] = threshold;
  d["tp"] = tp;
  d["fp"] = fp;
  d["fn"] = fn;
  d["precision"] = precision;
  d["recall"] = recall;
  d["similarity"] = similarity;
  d["orientation"] = orientation;
  return d;
}

py::array_t<double> Doubles(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

py::dict FilteredCurveDict(const FilteredCurve& c) {
  py::dict d;
  d["curve"] = CurveDict(c.curve);
  d["ap_r40"] = c.ap_r40;
  d["ap_r11"] = c.ap_r11;
  d["ap_voc"] = c.ap_voc;
  d["aos_r40"] = c.aos_r40;
  d["aos_r11"] = c.aos_r11;
  d["apl_r40"] = c.apl_r40;
  d["apl_r11"] = c.apl_r11;
  return d;
}

// A fixed-width numpy str column ("<U{width}") filled without a Python string per row.
template <typename GetText>
py::array StringColumn(size_t n, GetText text) {
  size_t width = 1;
  for (size_t i = 0; i < n; ++i) width = std::max(width, std::string_view(text(i)).size());
  py::array out(py::dtype("<U" + std::to_string(width)),
                std::vector<py::ssize_t>{static_cast<py::ssize_t>(n)});
  auto* data = static_cast<uint32_t*>(out.mutable_data());
  std::fill(data, data + n * width, 0u);
  for (size_t i = 0; i < n; ++i) {
    const std::string_view s = text(i);
    for (size_t k = 0; k < s.size(); ++k) data[i * width + k] = static_cast<unsigned char>(s[k]);
  }
  return out;
}

// One row per cell, with the headline numbers: what pandas.DataFrame(rows) takes.
py::list Rows(const PyEvalResult& r) {
  py::list rows;
  for (const EvalRun& run : r.Selected()) {
    const std::string overlaps = DescribeOverlaps(run.options.classes);
    for (const ClassResult& c : run.result.results) {
      py::dict row;
      row["class"] = c.class_name;
      row["metric"] = OverlapKindName(c.metric);
      row["difficulty"] = DifficultyName(c.difficulty);
      row["overlaps"] = overlaps;
      row["min_overlap"] = c.min_overlap;
      row["evaluated"] = c.evaluated;
      const double nan = std::nan("");
      auto v = [&](double x) { return c.evaluated ? x : nan; };
      row["num_valid_labels"] = c.num_valid_labels;
      row["small_sample"] = IsSmallSample(c);
      row["num_detections"] = c.num_detections;
      row["ap_r40"] = v(c.ap_r40);
      row["ap_r11"] = v(c.ap_r11);
      row["ap_voc"] = v(c.ap_voc);
      row["aos_r40"] = v(c.aos_r40);
      row["aos_r11"] = v(c.aos_r11);
      row["apl_r40"] = v(c.apl_r40);
      row["apl_r11"] = v(c.apl_r11);
      row["threshold"] = v(c.at_threshold.threshold);
      row["tp"] = c.at_threshold.tp;
      row["fp"] = c.at_threshold.fp;
      row["fn"] = c.at_threshold.fn;
      row["precision"] = v(c.at_threshold.precision);
      row["recall"] = v(c.at_threshold.recall);
      row["f1"] = v(c.at_threshold.f1);
      row["best_f1"] = v(c.best_f1.f1);
      row["best_f1_threshold"] = v(c.best_f1.threshold);
      row["brier_over_labels"] = v(c.brier.over_labels);
      row["brier_over_detections"] = v(c.brier.over_detections);
      row["brier_over_all"] = v(c.brier.over_all);
      row["ece"] = v(c.calibration.ece);
      row["laece"] = v(c.calibration.laece);
      row["dece"] = v(c.calibration.dece);
      rows.append(row);
    }
  }
  return rows;
}

// Every cell's records (EvalOptions::keep_records) as columns of equal length.
py::dict Records(const PyEvalResult& r) {
  if (r.Several()) {
    ThrowValueError("records: one per overlap set; take result.runs[i].records()");
  }
  const EvalRun& run = r.First();
  if (!run.options.keep_records) {
    ThrowValueError("no records: evaluate with records=True to keep them");
  }
  struct Row {
    const ClassResult* cell;
    const MatchRecord* record;
  };
  std::vector<Row> rows;
  for (const ClassResult& c : run.result.results) {
    for (const MatchRecord& m : c.records) rows.push_back({&c, &m});
  }
  const auto n = static_cast<py::ssize_t>(rows.size());
  py::array_t<int32_t> frame(n), detection(n), label(n);
  py::array_t<double> min_overlap(n), score(n), iou(n);
  py::array_t<bool> label_valid(n);
  const std::vector<EvalFrame>& frames = *r.frames;
  for (py::ssize_t i = 0; i < n; ++i) {
    const MatchRecord& m = *rows[i].record;
    frame.mutable_data()[i] = m.frame;
    detection.mutable_data()[i] = m.detection;
    label.mutable_data()[i] = m.label;
    min_overlap.mutable_data()[i] = rows[i].cell->min_overlap;
    score.mutable_data()[i] =
        m.detection >= 0 ? frames[m.frame].detections[m.detection].score.value_or(std::nan(""))
                         : std::nan("");
    iou.mutable_data()[i] = m.iou;
    label_valid.mutable_data()[i] = m.label_valid;
  }
  py::dict d;
  d["frame"] = frame;
  d["frame_id"] = StringColumn(
      rows.size(), [&](size_t i) -> std::string_view { return frames[rows[i].record->frame].id; });
  d["class"] = StringColumn(rows.size(),
                            [&](size_t i) -> std::string_view { return rows[i].cell->class_name; });
  d["metric"] = StringColumn(rows.size(), [&](size_t i) -> std::string_view {
    return OverlapKindName(rows[i].cell->metric);
  });
  d["difficulty"] = StringColumn(rows.size(), [&](size_t i) -> std::string_view {
    return DifficultyName(rows[i].cell->difficulty);
  });
  d["min_overlap"] = min_overlap;
  d["outcome"] = StringColumn(rows.size(), [&](size_t i) -> std::string_view {
    return OutcomeName(rows[i].record->outcome);
  });
  d["detection"] = detection;
  d["label"] = label;
  d["score"] = score;
  d["iou"] = iou;
  d["label_valid"] = label_valid;
  return d;
}

py::object ToDict(const PyEvalResult& r) {
  std::string text;
  {
    ReleaseGil release;
    const std::span<const EvalRun> runs = r.Selected();
    // The run(s) as EvalRun, so that bootstrap intervals come along (results.json's layout).
    text = (runs.size() == 1 ? EvalResultToJson(std::vector<EvalRun>{runs[0]}, r.info)
                             : EvalResultToJson(*r.runs, r.info))
               .dump();
  }
  return py::module_::import("json").attr("loads")(text);
}

py::list SweepRowsList(const std::vector<SweepRow>& rows, FilterBound b) {
  py::list out;
  for (const SweepRow& r : rows) {
    py::dict d;
    d["class"] = r.class_name;
    d["metric"] = OverlapKindName(r.metric);
    d["difficulty"] = DifficultyName(r.difficulty);
    d["filter"] = FilterBoundName(b);
    d["value"] = r.value;
    for (const auto& [name, p] :
         {std::pair{"naive", &r.stats.naive}, std::pair{"stable", &r.stats.stable}}) {
      const std::string prefix = name;
      d[py::str(prefix + "_tp")] = p->tp;
      d[py::str(prefix + "_fp")] = p->fp;
      d[py::str(prefix + "_fn")] = p->fn;
      d[py::str(prefix + "_precision")] = p->precision;
      d[py::str(prefix + "_recall")] = p->recall;
    }
    out.append(d);
  }
  return out;
}

py::list CompareRowsList(const std::vector<CompareRow>& rows) {
  py::list out;
  for (const CompareRow& r : rows) {
    py::dict d;
    d["class"] = r.class_name;
    d["metric"] = OverlapKindName(r.metric);
    d["difficulty"] = DifficultyName(r.difficulty);
    d["lower_m"] = r.lower_m;
    d["upper_m"] = r.upper_m;
    d["count_a"] = r.count_a;
    d["count_b"] = r.count_b;
    d["abs_depth_error_mean_a_m"] = r.abs_depth_error_mean_a_m;
    d["abs_depth_error_mean_b_m"] = r.abs_depth_error_mean_b_m;
    d["difference_b_minus_a_m"] = r.difference_b_minus_a_m;
    d["centre_error_mean_a_m"] = r.centre_error_mean_a_m;
    d["centre_error_mean_b_m"] = r.centre_error_mean_b_m;
    d["model_depth_error_m"] = r.model_depth_error_m;
    out.append(d);
  }
  return out;
}

std::string Table(const PyEvalResult& r) {
  const std::span<const EvalRun> runs = r.Selected();
  ReleaseGil release;
  return runs.size() == 1 ? FormatEvalTable(runs[0].result, runs[0].options)
                          : FormatEvalTable(*r.runs);
}

// The cell of the run of `overlaps` (DescribeOverlaps' name; with one run, optional).
const ClassResult* FindCell(const PyEvalResult& r, const std::string& class_name,
                            const std::string& metric, py::handle difficulty,
                            const std::optional<std::string>& overlaps) {
  const OverlapKind kind = ParseKind(metric);
  const Difficulty d = ParseDifficulty(difficulty);
  if (!overlaps.has_value()) {
    if (r.Several()) {
      ThrowValueError("several overlap sets: give overlaps= (one of the result's overlaps)");
    }
    return r.First().result.Find(class_name, kind, d);
  }
  std::string names;
  for (const EvalRun& run : r.Selected()) {
    const std::string name = DescribeOverlaps(run.options.classes);
    if (EqualsIgnoreCase(name, *overlaps)) return run.result.Find(class_name, kind, d);
    if (!names.empty()) names += ", ";
    names += name;
  }
  ThrowValueError("overlaps: no run '" + *overlaps + "' (" + names + ")");
}

// ClassSpec::min_overlap of three thresholds (2D, BEV, 3D; the LET kinds take BEV's and 3D's, as
// KittiClassSpec's) or five.
std::array<double, kNumOverlapKinds> MinOverlaps(const std::vector<double>& v) {
  if (v.size() == 3) return {v[0], v[1], v[2], v[1], v[2]};
  if (v.size() == 5) return {v[0], v[1], v[2], v[3], v[4]};
  throw std::invalid_argument(
      "min_overlap: 3 thresholds (2D, BEV, 3D) or 5 (and LET-BEV, LET-3D), got " +
      std::to_string(v.size()));
}

void BindClassSpec(py::module_& m) {
  py::class_<ClassSpec>(m, "ClassSpec",
                        R"(One evaluated class: its name (compared case-insensitively, as
the devkit does), the neighbour classes whose labels are ignored (Car: Van; Pedestrian:
Person_sitting) and the minimum overlap for a match in 2D, BEV and 3D (and LET-BEV,
LET-3D: three values give them BEV's and 3D's).)")
      .def(py::init([](std::string name, std::vector<std::string> neighbours,
                       const std::vector<double>& min_overlap) {
             ClassSpec spec;
             spec.name = std::move(name);
             spec.neighbours = std::move(neighbours);
             spec.min_overlap = MinOverlaps(min_overlap);
             return spec;
           }),
           py::arg("name"), py::arg("neighbours") = std::vector<std::string>{},
           py::arg("min_overlap") = std::vector<double>{0.5, 0.5, 0.5})
      .def_readwrite("name", &ClassSpec::name)
      .def_readwrite("neighbours", &ClassSpec::neighbours)
      .def_property(
          "min_overlap",
          [](const ClassSpec& c) {
            return std::vector<double>(c.min_overlap.begin(), c.min_overlap.end());
          },
          [](ClassSpec& c, const std::vector<double>& v) { c.min_overlap = MinOverlaps(v); },
          "(2D, BEV, 3D, LET-BEV, LET-3D); set with three (the LET kinds then take BEV's and "
          "3D's) or five")
      .def("__repr__", [](const ClassSpec& c) {
        return py::str("ClassSpec({!r}, neighbours={!r}, min_overlap={!r})")
            .format(c.name, c.neighbours, c.min_overlap)
            .cast<std::string>();
      });
  m.def("_kitti_class_spec", &KittiClassSpec, py::arg("name"), py::arg("loose") = false);
  m.def("_openpcdet_class_spec", &OpenPcdetClassSpec, py::arg("name"), py::arg("loose") = false);
}

void BindEvalOptions(py::module_& m) {
  py::class_<EvalOptions>(m, "EvalOptions",
                          "The evaluator's options (eval/eval_options.h); built by "
                          "stereodet.evaluate() from its keyword arguments.")
      .def(py::init<>())
      .def_readwrite("classes", &EvalOptions::classes)
      .def_property(
          "metrics",
          [](const EvalOptions& o) {
            std::vector<std::string> out;
            for (OverlapKind k : o.metrics) out.emplace_back(OverlapKindName(k));
            return out;
          },
          [](EvalOptions& o, const std::vector<std::string>& names) {
            o.metrics.clear();
            for (const std::string& n : names) o.metrics.push_back(ParseKind(n));
          })
      .def_property(
          "difficulties",
          [](const EvalOptions& o) {
            std::vector<std::string> out;
            for (Difficulty d : o.difficulties) out.emplace_back(DifficultyName(d));
            return out;
          },
          [](EvalOptions& o, const py::iterable& values) {
            o.difficulties.clear();
            for (py::handle v : values) o.difficulties.push_back(ParseDifficulty(v));
          })
      .def_property(
          "matcher", [](const EvalOptions& o) { return std::string(MatcherName(o.matcher)); },
          [](EvalOptions& o, const std::string& s) {
            o.matcher = ParseChoice([](const std::string& t) { return ParseMatcher(t); }, s,
                                    "matcher", "kitti, optimal, voc");
          })
      .def_property(
          "compat", [](const EvalOptions& o) { return std::string(EvalCompatName(o.compat)); },
          [](EvalOptions& o, const std::string& s) {
            o.compat = ParseChoice([](const std::string& t) { return ParseEvalCompat(t); }, s,
                                   "compat", "devkit, openpcdet");
          })
      .def_property(
          "score_transform",
          [](const EvalOptions& o) { return std::string(ScoreTransformName(o.score_transform)); },
          [](EvalOptions& o, const std::string& s) {
            o.score_transform =
                ParseChoice([](const std::string& t) { return ParseScoreTransform(t); }, s,
                            "score_transform", "none, sigmoid");
          })
      .def_property(
          "filters", [](const EvalOptions& o) { return ConditionsText(o.filter.conditions); },
          [](EvalOptions& o, py::handle v) { o.filter.conditions = ParseConditions(v); })
      .def_property(
          "breakdowns",
          [](const EvalOptions& o) {
            std::vector<std::string> texts;
            for (const BreakdownOptions& b : o.breakdowns) texts.push_back(BreakdownText(b));
            return texts;
          },
          [](EvalOptions& o, py::handle v) {
            std::vector<std::string> texts;
            if (py::isinstance<py::str>(v)) {
              texts.push_back(v.cast<std::string>());
            } else {
              texts = v.cast<std::vector<std::string>>();
            }
            o.breakdowns.clear();
            for (const std::string& text : texts) o.breakdowns.push_back(ParseBreakdown(text));
          },
          "breakdowns as the CLI's --breakdown text, e.g. [\"distance=0,30,50,inf\"]")
      .def_property(
          "filter_mode",
          [](const EvalOptions& o) { return std::string(FilterModeName(o.filter.mode)); },
          [](EvalOptions& o, const std::string& s) {
            o.filter.mode = ParseChoice([](const std::string& t) { return ParseFilterMode(t); }, s,
                                        "filter_mode", "naive, stable");
          })
      .def_readwrite("score_threshold", &EvalOptions::score_threshold)
      .def_readwrite("require_detections", &EvalOptions::require_detections)
      .def_readwrite("compute_aos", &EvalOptions::compute_aos)
      .def_readwrite("calibration_bins", &EvalOptions::calibration_bins)
      .def_readwrite("distance_bin_m", &EvalOptions::distance_bin_m)
      .def_readwrite("max_distance_m", &EvalOptions::max_distance_m)
      .def_readwrite("keep_records", &EvalOptions::keep_records)
      .def_readwrite("breakdown_naive", &EvalOptions::breakdown_naive,
                     "also each breakdown bin evaluated on its own (the CLI's --breakdown-naive)")
      .def_readwrite("num_threads", &EvalOptions::num_threads)
      .def("check", &EvalOptions::Check, "Raises ValueError on a bad setting.");
}

void BindResults(py::module_& m) {
  py::class_<ClassResult>(m, "ClassResult",
                          R"(One class x overlap kind x difficulty of an evaluation.

AP and AOS are in percent (ap_voc is NaN for the KITTI matcher, aos_* NaN where AOS is not
computed); `evaluated` is False where the devkit would skip the class (then nothing else is
filled). docs/metrics.md defines every number.)")
      .def_readonly("class_name", &ClassResult::class_name)
      .def_property_readonly("metric",
                             [](const ClassResult& c) { return OverlapKindName(c.metric); })
      .def_property_readonly("difficulty",
                             [](const ClassResult& c) { return DifficultyName(c.difficulty); })
      .def_readonly("min_overlap", &ClassResult::min_overlap)
      .def_readonly("evaluated", &ClassResult::evaluated)
      .def_readonly("num_valid_labels", &ClassResult::num_valid_labels)
      .def_readonly("num_detections", &ClassResult::num_detections)
      .def_readonly("ap_r40", &ClassResult::ap_r40)
      .def_readonly("ap_r11", &ClassResult::ap_r11)
      .def_readonly("ap_voc", &ClassResult::ap_voc)
      .def_readonly("aos_r40", &ClassResult::aos_r40)
      .def_readonly("aos_r11", &ClassResult::aos_r11)
      .def_readonly("has_aos", &ClassResult::has_aos)
      .def_readonly("apl_r40", &ClassResult::apl_r40,
                    "LET-APL in percent (metrics let-bev, let-3d; NaN otherwise)")
      .def_readonly("apl_r11", &ClassResult::apl_r11)
      .def_readonly("has_apl", &ClassResult::has_apl)
      .def_property_readonly("small_sample", &IsSmallSample,
                             "True for 40 valid labels or fewer (the KITTI matcher's AP_R40 cap)")
      .def_property_readonly(
          "at_threshold", [](const ClassResult& c) { return OperatingPointDict(c.at_threshold); })
      .def_property_readonly("best_f1",
                             [](const ClassResult& c) { return OperatingPointDict(c.best_f1); })
      .def_property_readonly(
          "curve", [](const ClassResult& c) { return CurveDict(c.curve); },
          "dict of arrays, one entry per threshold (descending)")
      .def_property_readonly("kitti_precision",
                             [](const ClassResult& c) { return Doubles(c.kitti_precision); })
      .def_property_readonly("kitti_aos", [](const ClassResult& c) { return Doubles(c.kitti_aos); })
      .def_property_readonly("kitti_thresholds",
                             [](const ClassResult& c) { return Doubles(c.kitti_thresholds); })
      .def_property_readonly("filtered",
                             [](const ClassResult& c) -> py::object {
                               if (!c.filtered) return py::none();
                               py::dict d;
                               d["naive"] = OperatingPointDict(c.filtered->naive);
                               d["stable"] = OperatingPointDict(c.filtered->stable);
                               d["naive_curve"] = FilteredCurveDict(c.filtered->naive_curve);
                               d["stable_curve"] = FilteredCurveDict(c.filtered->stable_curve);
                               return d;
                             })
      .def_property_readonly(
          "breakdown",
          [](const ClassResult& c) {
            py::list bins;
            for (const BreakdownBin& b : c.breakdown) {
              py::dict d;
              d["axis"] = BreakdownAxisName(b.axis);
              d["bin"] = BreakdownBinName(b.lower, b.upper);
              d["lower"] = b.lower;
              d["upper"] = b.upper;
              d["num_valid_labels"] = b.num_valid_labels;
              d["at_threshold"] = OperatingPointDict(b.at_threshold);
              d["curve"] = FilteredCurveDict(b.curve);
              d["brier_over_labels"] = b.brier.over_labels;
              d["brier_over_detections"] = b.brier.over_detections;
              d["brier_over_all"] = b.brier.over_all;
              if (b.naive) {
                py::dict naive;
                naive["num_valid_labels"] = b.naive->num_valid_labels;
                naive["at_threshold"] = OperatingPointDict(b.naive->at_threshold);
                naive["curve"] = FilteredCurveDict(b.naive->curve);
                d["naive"] = naive;
              } else {
                d["naive"] = py::none();
              }
              bins.append(d);
            }
            return bins;
          },
          "with EvalOptions.breakdowns: one dict per bin (axis, bin, lower, upper, "
          "num_valid_labels, at_threshold, curve, brier_*, and naive: with "
          "EvalOptions.breakdown_naive the bin evaluated on its own {num_valid_labels, "
          "at_threshold, curve}, else None), breakdowns in order, bins ascending")
      .def_property_readonly("brier",
                             [](const ClassResult& c) {
                               py::dict d;
                               d["over_labels"] = c.brier.over_labels;
                               d["num_label_terms"] = c.brier.num_label_terms;
                               d["over_detections"] = c.brier.over_detections;
                               d["num_detection_terms"] = c.brier.num_detection_terms;
                               d["over_all"] = c.brier.over_all;
                               d["num_all_terms"] = c.brier.num_all_terms;
                               return d;
                             })
      .def_property_readonly("ece", [](const ClassResult& c) { return c.calibration.ece; })
      .def_property_readonly("laece", [](const ClassResult& c) { return c.calibration.laece; })
      .def_property_readonly(
          "dece", [](const ClassResult& c) { return c.calibration.dece; },
          "D-ECE over (score, box centre, box size) bins (docs/metrics.md, Calibration)")
      .def("__repr__", [](const ClassResult& c) {
        return "<ClassResult " + c.class_name + " " + OverlapKindName(c.metric) + " " +
               DifficultyName(c.difficulty) +
               (c.evaluated ? " AP_R40 " + std::to_string(c.ap_r40)
                            : std::string(" not evaluated")) +
               ">";
      });

  py::class_<PyEvalResult>(m, "EvalResult",
                           R"(The result of stereodet.evaluate(): one run per overlap set.

  cells            every class x overlap kind x difficulty (ClassResult), in option order
                   (with several overlap sets: every run's, in run order)
  find(c, m, d)    one of them, or None; ap(c, m, d) its AP (overlaps= picks the run)
  runs             one EvalResult per overlap set (the CLI's --overlaps strict,loose)
  to_dict()        the CLI's results.json, as plain Python (NaN as None)
  rows()           one flat dict per cell: pandas.DataFrame(result.rows())
  records()        with records=True: what every detection and label counts as, numpy columns
  table()          the CLI's text table (also str(result))
  files            with out=: the files written)")
      .def_property_readonly("num_frames",
                             [](const PyEvalResult& r) { return r.First().result.num_frames; })
      .def_property_readonly("aos_computed",
                             [](const PyEvalResult& r) { return r.First().result.aos_computed; })
      .def_property_readonly(
          "probability_metrics",
          [](const PyEvalResult& r) { return r.First().result.probability_metrics; })
      .def_property_readonly(
          "seconds",
          [](const PyEvalResult& r) {
            double seconds = 0;
            for (const EvalRun& run : r.Selected()) seconds += run.result.seconds;
            return seconds;
          },
          "wall time of the evaluation (the C++ Evaluate(), summed over the runs)")
      .def_property_readonly(
          "options", [](const PyEvalResult& r) { return r.First().options; },
          "the options (with several runs the first run's; runs[i].options each)")
      .def_property_readonly(
          "overlaps",
          [](const PyEvalResult& r) {
            std::vector<std::string> out;
            for (const EvalRun& run : r.Selected()) {
              out.push_back(DescribeOverlaps(run.options.classes));
            }
            return out;
          },
          "the overlap set of each run: ['strict'], ['strict', 'loose'] (or 'custom')")
      .def_property_readonly(
          "runs",
          [](const PyEvalResult& r) {
            std::vector<PyEvalResult> out;
            const int first = r.index < 0 ? 0 : r.index;
            for (int i = 0; i < static_cast<int>(r.Selected().size()); ++i) {
              PyEvalResult one = r;
              one.index = first + i;
              out.push_back(std::move(one));
            }
            return out;
          },
          "one EvalResult per overlap set, in the order given (one: [a result equal to this])")
      .def_property_readonly(
          "files", [](const PyEvalResult& r) { return r.files; },
          "the files written with out= (empty without)")
      .def_property_readonly(
          "cells",
          [](py::object self) {
            const PyEvalResult& r = self.cast<const PyEvalResult&>();
            py::list out;
            for (const EvalRun& run : r.Selected()) {
              for (const ClassResult& c : run.result.results) {
                out.append(py::cast(&c, py::return_value_policy::reference_internal, self));
              }
            }
            return out;
          })
      .def(
          "find",
          [](py::object self, const std::string& class_name, const std::string& metric,
             py::handle difficulty, const std::optional<std::string>& overlaps) -> py::object {
            const PyEvalResult& r = self.cast<const PyEvalResult&>();
            const ClassResult* c = FindCell(r, class_name, metric, difficulty, overlaps);
            if (c == nullptr) return py::none();
            return py::cast(c, py::return_value_policy::reference_internal, self);
          },
          py::arg("class_name"), py::arg("metric") = "3d", py::arg("difficulty") = "moderate",
          py::kw_only(), py::arg("overlaps") = py::none(),
          "The cell of a class (case-insensitive), metric (2d, bev, 3d) and difficulty, or None; "
          "with several overlap sets, overlaps= says of which run.")
      .def(
          "ap",
          [](const PyEvalResult& r, const std::string& class_name, const std::string& metric,
             py::handle difficulty, const std::string& recall,
             const std::optional<std::string>& overlaps) {
            const ClassResult* c = FindCell(r, class_name, metric, difficulty, overlaps);
            if (c == nullptr) {
              ThrowValueError("no result for " + class_name + " " + metric + " " +
                              py::str(difficulty).cast<std::string>());
            }
            if (!c->evaluated) return std::nan("");
            if (recall == "r40") return c->ap_r40;
            if (recall == "r11") return c->ap_r11;
            if (recall == "voc") return c->ap_voc;
            ThrowValueError("recall: unknown '" + recall + "' (r40, r11, voc)");
          },
          py::arg("class_name"), py::arg("metric") = "3d", py::arg("difficulty") = "moderate",
          py::arg("recall") = "r40", py::kw_only(), py::arg("overlaps") = py::none(),
          "AP in percent (NaN where the class was not evaluated).")
      .def("to_dict", &ToDict,
           "The CLI's results.json as plain Python: the same keys and numbers (NaN as None).")
      .def("rows", &Rows, "One flat dict per cell (pandas.DataFrame(result.rows())).")
      .def("records", &Records,
           "Per-detection records (evaluate with records=True): a dict of numpy columns frame, "
           "frame_id, class, metric, difficulty, min_overlap, outcome (tp, fp, fn, ignored, "
           "dontcare), detection and label (indices in file order, -1 for none), score, iou, "
           "label_valid; one row per record, cells in result order. One overlap set at a time "
           "(runs[i].records()).")
      .def("table", &Table, "The CLI's text table.")
      .def("__str__", &Table)
      .def("__repr__", [](const PyEvalResult& r) {
        const EvalRun& run = r.First();
        size_t cells = 0;
        for (const EvalRun& one : r.Selected()) cells += one.result.results.size();
        std::string overlaps;
        for (const EvalRun& one : r.Selected()) {
          if (!overlaps.empty()) overlaps += ',';
          overlaps += DescribeOverlaps(one.options.classes);
        }
        return "<stereodet.EvalResult " + std::to_string(run.result.num_frames) + " frames, " +
               std::to_string(cells) + " cells, matcher " + MatcherName(run.options.matcher) +
               (r.Several() ? ", overlaps " + overlaps : std::string()) + ">";
      });
}

}  // namespace

void BindEval(py::module_& m) {
  BindClassSpec(m);
  BindEvalOptions(m);
  BindResults(m);

  py::class_<PyFrames>(m, "_Frames", "Frames converted for the evaluator (internal).")
      .def_property_readonly("num_frames", [](const PyFrames& f) { return f.frames->size(); })
      .def_property_readonly("notices", [](const PyFrames& f) { return f.notices; })
      .def_property_readonly("ids", [](const PyFrames& f) {
        std::vector<std::string> ids;
        for (const EvalFrame& e : *f.frames) ids.push_back(e.id);
        return ids;
      });
  m.def("_frames_from_annos", &FramesFromAnnos, py::arg("gt_annos"), py::arg("dt_annos"));
  m.def("_frames_from_folders", &FramesFromFolders, py::arg("gt"), py::arg("det"), py::arg("split"),
        py::arg("lenient"), py::arg("num_threads"), py::arg("missing_as_empty") = false,
        py::arg("score_if_missing") = std::nullopt);
  m.def("_evaluate", &EvaluateFrames, py::arg("frames"), py::arg("options"),
        py::arg("bootstrap") = 0, py::arg("bootstrap_seed") = 1,
        py::arg("bootstrap_confidence") = 0.95, py::arg("bootstrap_method") = "percentile");

  // get_official_eval_result's two evaluations, strict and loose, and its printout. The same
  // options as OpenPcdetPrintout (openpcdet_compat.cc) builds, so the printout is `stereodet eval
  // --compat openpcdet`'s.
  m.def(
      "_openpcdet_eval",
      [](const PyFrames& frames, const std::vector<std::string>& class_names, int num_threads) {
        EvalOptions base;
        base.matcher = Matcher::kKitti;
        base.compat = EvalCompat::kOpenPcdet;
        base.num_threads = num_threads;
        EvalOptions strict = base, loose = base;
        strict.classes.clear();
        loose.classes.clear();
        for (const std::string& name : class_names) {
          strict.classes.push_back(OpenPcdetClassSpec(name, false));
          loose.classes.push_back(OpenPcdetClassSpec(name, true));
        }
        PyEvalResult s = EvaluateFrames(frames, {strict}), l = EvaluateFrames(frames, {loose});
        std::string text;
        {
          ReleaseGil release;
          text = FormatOpenPcdetResult(s.First().result, l.First().result);
        }
        return py::make_tuple(text, std::move(s), std::move(l));
      },
      py::arg("frames"), py::arg("class_names"), py::arg("num_threads"));

  m.def("_overlap_set_runs", &OverlapRuns, py::arg("base"), py::arg("overlaps"),
        "OverlapSetRuns: base once per overlap set (names), with that set's class specs.");
  m.def("_run_evaluation", &RunFolders, py::arg("gt"), py::arg("det"), py::arg("split"),
        py::arg("lenient"), py::arg("num_threads"), py::arg("runs"), py::arg("out"),
        py::arg("records"), py::arg("missing_as_empty") = false,
        py::arg("score_if_missing") = std::nullopt, py::arg("bootstrap") = 0,
        py::arg("bootstrap_seed") = 1, py::arg("bootstrap_confidence") = 0.95,
        py::arg("bootstrap_method") = "percentile");
  m.def("_write_report", &WriteReport, py::arg("result"), py::arg("out"), py::arg("records"));

  // The TIDE-style error analysis of every cell (AnalyzeAllErrors), each as results.json's
  // "errors" (ErrorAnalysisJson) with its class, metric and difficulty, as one JSON text.
  m.def(
      "_analyze_errors",
      [](const PyFrames& frames, const EvalOptions& options, double background_overlap) {
        ErrorAnalysisOptions ea;
        ea.background_overlap = background_overlap;
        std::string text;
        {
          ReleaseGil release;
          options.Check();
          ea.Check();
          nlohmann::json cells = nlohmann::json::array();
          for (const ErrorAnalysis& a : AnalyzeAllErrors(*frames.frames, options, ea)) {
            nlohmann::json j = ErrorAnalysisJson(a);
            j["class"] = a.class_name;
            j["metric"] = OverlapKindName(a.kind);
            j["difficulty"] = DifficultyName(a.difficulty);
            j["evaluated"] = a.evaluated;
            cells.push_back(std::move(j));
          }
          text = cells.dump();
        }
        return text;
      },
      py::arg("frames"), py::arg("options"), py::arg("background_overlap"));
  m.def(
      "_filter_sweep",
      [](const PyFrames& frames, const EvalOptions& options, const std::string& bound, double from,
         double to, double step) {
        const FilterBound b = ParseBound(bound);
        std::vector<SweepRow> rows;
        {
          ReleaseGil release;
          options.Check();
          rows = FilterSweep(*frames.frames, options, b, from, to, step);
        }
        return SweepRowsList(rows, b);
      },
      py::arg("frames"), py::arg("options"), py::arg("bound"), py::arg("start"), py::arg("stop"),
      py::arg("step"));
  m.def(
      "_run_sweep",
      [](const fs::path& gt, const fs::path& det, const std::string& split, bool lenient,
         const EvalOptions& eval, const std::string& bound, double from, double to, double step,
         const fs::path& out, bool missing_as_empty) {
        EvaluationSweepOptions options;
        options.input = InputOptions(gt, det, split, lenient, eval.num_threads, missing_as_empty);
        options.eval = eval;
        options.bound = ParseBound(bound);
        options.from = from;
        options.to = to;
        options.step = step;
        options.out = out;
        EvaluationSweepResult result;
        {
          ReleaseGil release;
          result = RunEvaluationSweep(options);
        }
        return SweepRowsList(result.rows, options.bound);
      },
      py::arg("gt"), py::arg("det"), py::arg("split"), py::arg("lenient"), py::arg("options"),
      py::arg("bound"), py::arg("start"), py::arg("stop"), py::arg("step"), py::arg("out"),
      py::arg("missing_as_empty") = false);

  m.def(
      "_compare",
      [](const PyEvalResult& a, const PyEvalResult& b, double baseline_m, double focal_px,
         double disparity_error_px) {
        CompareOptions options;
        options.baseline_m = baseline_m;
        options.focal_px = focal_px;
        options.disparity_error_px = disparity_error_px;
        std::vector<CompareRow> rows;
        {
          ReleaseGil release;
          options.Check();
          rows = CompareLocalization(a.First().result, b.First().result, options);
        }
        return CompareRowsList(rows);
      },
      py::arg("a"), py::arg("b"), py::arg("baseline_m"), py::arg("focal_px"),
      py::arg("disparity_error_px"));
  m.def(
      "_run_compare",
      [](const fs::path& gt, const fs::path& det_a, const fs::path& det_b, const std::string& split,
         bool lenient, const EvalOptions& eval, const fs::path& calib, double disparity_error_px,
         const fs::path& out, bool missing_as_empty) {
        EvaluationCompareOptions options;
        options.input = InputOptions(gt, det_a, split, lenient, eval.num_threads, missing_as_empty);
        options.det_b = det_b;
        options.eval = eval;
        options.calib = calib;
        options.disparity_error_px = disparity_error_px;
        options.out = out;
        EvaluationCompareResult result;
        {
          ReleaseGil release;
          result = RunEvaluationCompare(options);
        }
        return CompareRowsList(result.rows);
      },
      py::arg("gt"), py::arg("det_a"), py::arg("det_b"), py::arg("split"), py::arg("lenient"),
      py::arg("options"), py::arg("calib"), py::arg("disparity_error_px"), py::arg("out"),
      py::arg("missing_as_empty") = false);
}

}  // namespace stereodet::python
