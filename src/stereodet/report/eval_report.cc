#include "stereodet/report/eval_report.h"

#include <fmt/format.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <optional>
#include <sstream>

#include "stereodet/report/bootstrap_report.h"
#include "stereodet/report/error_report.h"
#include "stereodet/report/report_json_internal.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

using nlohmann::json;

// A CalibrationResult: ECE, LaECE, counts and the reliability bins.
json CalibrationJson(const CalibrationResult& c) {
  json bins = json::array();
  for (const ReliabilityBin& b : c.bins) {
    bins.push_back({{"lower", b.lower},
                    {"upper", b.upper},
                    {"count", b.count},
                    {"mean_score", b.mean_score},
                    {"tp_fraction", b.tp_fraction},
                    {"mean_iou", b.mean_iou}});
  }
  return {{"ece", c.ece},
          {"laece", c.laece},
          {"dece", c.dece},
          {"dece_outside", c.dece_outside},
          {"num_detections", c.num_detections},
          {"num_out_of_range", c.num_out_of_range},
          {"bins", bins}};
}

json OperatingPointJson(const OperatingPoint& op) {
  return json{{"threshold", op.threshold}, {"tp", op.tp},         {"fp", op.fp}, {"fn", op.fn},
              {"precision", op.precision}, {"recall", op.recall}, {"f1", op.f1}};
}

std::string LowerName(const std::string& s) {
  std::string out = s;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string CurveStem(const ClassResult& r) {
  return LowerName(r.class_name) + "_" + OverlapKindName(r.metric) + "_" +
         LowerName(DifficultyName(r.difficulty));
}

using report_internal::Csv;

}  // namespace

std::string FormatNumber(double value, int decimals) {
  if (std::isnan(value)) return "-";
  return fmt::format("{:.{}f}", value, decimals);
}

namespace {

double FpPerFrame(const CurvePoint& p, int64_t num_frames) {
  return num_frames > 0 ? static_cast<double>(p.fp) / static_cast<double>(num_frames) : 0.0;
}

// Where a curve is: results.json names the CSV (relative to the results folder) that holds it
// exactly, and its number of points; the points themselves are too many for JSON (an exact curve
// has one per distinct score).
void AddCurveFile(json& e, const std::string& file, size_t points) {
  e["curve_csv"] = file;
  e["curve_points"] = points;
}

// `let`: the cell is of a LET kind (its APL added).
json FilteredCurveJson(const FilteredCurve& c, const std::string& file, bool let) {
  json e = {{"ap_r40", c.ap_r40},
            {"ap_r11", c.ap_r11},
            {"ap_voc", c.ap_voc},
            {"aos_r40", c.aos_r40},
            {"aos_r11", c.aos_r11}};
  if (let) {
    e["apl_r40"] = c.apl_r40;
    e["apl_r11"] = c.apl_r11;
  }
  AddCurveFile(e, file, c.curve.size());
  return e;
}

}  // namespace

namespace {

// min_overlap: 2D, BEV, 3D, and with `with_let` LET-BEV, LET-3D too (runs without a LET kind keep
// the three of their records).
json ClassesJson(const std::vector<ClassSpec>& specs, bool with_let) {
  json classes = json::array();
  for (const ClassSpec& c : specs) {
    const size_t n = with_let ? c.min_overlap.size() : 3;
    const std::vector<double> min_overlap(c.min_overlap.begin(), c.min_overlap.begin() + n);
    classes.push_back(
        {{"name", c.name}, {"neighbours", c.neighbours}, {"min_overlap", min_overlap}});
  }
  return classes;
}

json OptionsJson(const EvalOptions& options) {
  const bool with_let = options.HasLetKind();
  json metrics = json::array();
  for (OverlapKind k : options.metrics) metrics.push_back(OverlapKindName(k));
  json difficulties = json::array();
  for (Difficulty d : options.difficulties) difficulties.push_back(DifficultyName(d));
  json filter = json::array();
  for (const FilterCondition& c : options.filter.conditions) {
    filter.push_back({{"bound", FilterBoundName(c.bound)}, {"value", c.value}});
  }
  json j = {{"matcher", MatcherName(options.matcher)},
            {"compat", EvalCompatName(options.compat)},
            {"classes", ClassesJson(options.classes, with_let)},
            {"metrics", metrics},
            {"difficulties", difficulties},
            {"score_threshold", options.score_threshold},
            {"score_transform", ScoreTransformName(options.score_transform)},
            {"require_detections", options.require_detections},
            {"calibration_bins", options.calibration_bins},
            {"dece",
             {{"bins", options.dece.bins},
              {"image_width_px", options.dece.image_width_px},
              {"image_height_px", options.dece.image_height_px}}},
            {"distance_bin_m", options.distance_bin_m},
            {"max_distance_m", options.max_distance_m},
            {"filter", filter},
            {"filter_mode", FilterModeName(options.filter.mode)},
            {"num_threads", options.num_threads}};
  // Only when asked, so that the records of runs without one stay as they were.
  if (with_let) {
    const LetOptions& let = options.let;
    j["let"] = {{"longitudinal_tolerance_fraction", let.longitudinal_tolerance_fraction},
                {"min_longitudinal_tolerance_m", let.min_longitudinal_tolerance_m},
                {"sensor_m", {let.sensor_m.x(), let.sensor_m.y(), let.sensor_m.z()}}};
  }
  if (!options.breakdowns.empty()) {
    json breakdowns = json::array();
    for (const BreakdownOptions& b : options.breakdowns) breakdowns.push_back(BreakdownText(b));
    j["breakdowns"] = breakdowns;
    if (options.breakdown_naive) j["breakdown_naive"] = true;
  }
  return j;
}

// The curve CSVs' names of a cell: "curves/" + prefix + CurveStem + suffix + ".csv" (suffix: ""
// or "_OVERLAPS" with several runs).
std::string CurveFile(const std::string& prefix, const ClassResult& r, const std::string& suffix) {
  return "curves/" + prefix + CurveStem(r) + suffix + ".csv";
}

std::string RunSuffix(const std::vector<EvalRun>& runs, const EvalRun& run) {
  // (append, not "_" + string: g++ 12 warns falsely on the latter, -Wrestrict)
  std::string suffix;
  if (runs.size() > 1) suffix.append("_").append(DescribeOverlaps(run.options.classes));
  return suffix;
}

json ClassResultJson(const ClassResult& r, const std::string& overlaps, const std::string& suffix) {
  json e;
  e["class"] = r.class_name;
  e["metric"] = OverlapKindName(r.metric);
  e["difficulty"] = DifficultyName(r.difficulty);
  e["overlaps"] = overlaps;
  e["min_overlap"] = r.min_overlap;
  e["evaluated"] = r.evaluated;
  if (!r.evaluated) return e;
  e["num_valid_labels"] = r.num_valid_labels;
  e["small_sample"] = IsSmallSample(r);
  e["num_detections"] = r.num_detections;
  e["ap_r40"] = r.ap_r40;
  e["ap_r11"] = r.ap_r11;
  e["ap_voc"] = r.ap_voc;
  e["aos_r40"] = r.aos_r40;
  e["aos_r11"] = r.aos_r11;
  if (IsLetKind(r.metric)) {
    e["apl_r40"] = r.apl_r40;
    e["apl_r11"] = r.apl_r11;
  }
  e["at_threshold"] = OperatingPointJson(r.at_threshold);
  e["best_f1"] = OperatingPointJson(r.best_f1);
  if (r.filtered) {
    const FilteredStats& fs = *r.filtered;
    e["filtered"] = {
        {"naive", OperatingPointJson(fs.naive)},
        {"stable", OperatingPointJson(fs.stable)},
        {"naive_curve",
         FilteredCurveJson(fs.naive_curve, CurveFile("pr_naive_", r, suffix), IsLetKind(r.metric))},
        {"stable_curve", FilteredCurveJson(fs.stable_curve, CurveFile("pr_stable_", r, suffix),
                                           IsLetKind(r.metric))}};
  }
  if (!r.breakdown.empty()) {
    json bins = json::array();
    for (const BreakdownBin& b : r.breakdown) {
      // "upper": null is inf (JSON has no infinity); "bin" names it.
      bins.push_back({{"axis", BreakdownAxisName(b.axis)},
                      {"bin", BreakdownBinName(b.lower, b.upper)},
                      {"lower", b.lower},
                      {"upper", b.upper},
                      {"num_valid_labels", b.num_valid_labels},
                      {"at_threshold", OperatingPointJson(b.at_threshold)},
                      {"ap_r40", b.curve.ap_r40},
                      {"ap_r11", b.curve.ap_r11},
                      {"ap_voc", b.curve.ap_voc},
                      {"brier_over_labels", b.brier.over_labels},
                      {"brier_over_detections", b.brier.over_detections},
                      {"brier_over_all", b.brier.over_all},
                      {"calibration", CalibrationJson(b.calibration)}});
      if (IsLetKind(r.metric)) {
        bins.back()["apl_r40"] = b.curve.apl_r40;
        bins.back()["apl_r11"] = b.curve.apl_r11;
      }
      if (b.naive) {
        // The bin evaluated on its own (EvalOptions::breakdown_naive), for comparison.
        bins.back()["naive"] = {{"num_valid_labels", b.naive->num_valid_labels},
                                {"at_threshold", OperatingPointJson(b.naive->at_threshold)},
                                {"ap_r40", b.naive->curve.ap_r40},
                                {"ap_r11", b.naive->curve.ap_r11},
                                {"ap_voc", b.naive->curve.ap_voc}};
      }
    }
    e["breakdown"] = bins;
  }
  AddCurveFile(e, CurveFile("pr_", r, suffix), r.curve.size());
  e["roc_csv"] = CurveFile("roc_", r, suffix);
  if (!r.kitti_precision.empty()) {
    e["kitti"] = {
        {"precision", r.kitti_precision}, {"aos", r.kitti_aos}, {"thresholds", r.kitti_thresholds}};
    if (IsLetKind(r.metric)) e["kitti"]["apl"] = r.kitti_apl;
  }
  e["brier"] = {{"over_labels", r.brier.over_labels},
                {"num_label_terms", r.brier.num_label_terms},
                {"over_detections", r.brier.over_detections},
                {"num_detection_terms", r.brier.num_detection_terms},
                {"over_all", r.brier.over_all},
                {"num_all_terms", r.brier.num_all_terms}};
  e["calibration"] = CalibrationJson(r.calibration);
  json loc = json::array();
  for (const DistanceBin& b : r.localization) {
    loc.push_back({{"lower_m", b.lower_m},
                   {"upper_m", b.upper_m},
                   {"count", b.count},
                   {"centre_error_mean_m", b.centre_error_mean_m},
                   {"centre_error_median_m", b.centre_error_median_m},
                   {"centre_error_p90_m", b.centre_error_p90_m},
                   {"depth_error_mean_m", b.depth_error_mean_m},
                   {"abs_depth_error_mean_m", b.abs_depth_error_mean_m},
                   {"abs_depth_error_median_m", b.abs_depth_error_median_m},
                   {"abs_depth_error_p90_m", b.abs_depth_error_p90_m}});
  }
  e["localization"] = loc;
  return e;
}

std::vector<EvalRun> OneRun(const EvalResult& result, const EvalOptions& options) {
  return {EvalRun{options, result}};
}

}  // namespace

std::vector<std::string> EvalNotes(const std::vector<EvalRun>& runs) {
  std::vector<std::string> notes;
  if (runs.empty()) return notes;
  const EvalResult& first = runs.front().result;
  const ScoreSummary& sc = first.scores;
  const ScoreTransform transform = runs.front().options.score_transform;
  if (!first.probability_metrics) {
    notes.push_back(fmt::format(
        "scores outside [0, 1] ({} of {} detections, min {:.4g}, max {:.4g}) are not "
        "probabilities: Brier and ECE are left out; if they are logits, pass --score-transform "
        "sigmoid",
        sc.num_outside_unit, sc.num_scores, sc.min_score, sc.max_score));
  } else if (transform != ScoreTransform::kNone) {
    std::string note = fmt::format(
        "Brier and ECE on {}(score) (--score-transform); AP, curves and the operating point on the "
        "raw scores",
        ScoreTransformName(transform));
    if (sc.num_scores > 0 && sc.num_outside_unit == 0) {
      note += "; note: every raw score is in [0, 1] already";
    }
    notes.push_back(note);
  }
  bool small = false;
  for (const EvalRun& run : runs) {
    if (run.options.matcher != Matcher::kKitti) continue;
    for (const ClassResult& r : run.result.results) small |= IsSmallSample(r);
  }
  if (small) {
    notes.push_back(
        fmt::format("* {} or fewer valid labels: the devkit's AP_R40 is capped at (TP - 1) / 40 "
                    "there (26 perfect detections of 27 labels give 62.5); --matcher optimal "
                    "gives the exact AP",
                    kSmallSampleLabels));
  }
  return notes;
}

json EvalResultToJson(const std::vector<EvalRun>& runs, const EvalRunInfo& info) {
  STEREODET_CHECK(!runs.empty()) << "no evaluation run to write";
  const EvalRun& first = runs.front();
  json j;
  j["tool"] = {{"name", "stereodet eval"}, {"version", info.tool_version}};
  j["command_line"] = info.command_line;
  j["input_hash"] = info.input_hash;
  j["input"] = {{"gt", info.gt_path},
                {"det", info.det_path},
                {"split", info.split_path},
                {"num_frames", first.result.num_frames},
                {"num_frames_without_detections", info.frames_without_detections.size()},
                {"frames_without_detections", info.frames_without_detections},
                {"num_ignored_files", info.ignored_files.size()},
                {"ignored_files", info.ignored_files},
                {"lenient", info.lenient},
                {"score_if_missing", info.score_if_missing ? json(*info.score_if_missing) : json()},
                {"num_skipped_lines", info.skipped_lines.size()},
                {"skipped_lines", info.skipped_lines},
                {"det_run", info.det_run.empty() ? json() : json(info.det_run)},
                {"det_files_not_from_run", info.det_not_from_run}};
  // Only when given, so that the records of runs without one stay as they were.
  if (!info.calibration_path.empty()) {
    j["input"]["calibration"] = {{"file", info.calibration_path},
                                 {"calibrated_detections", info.calibrated_detections}};
  }
  j["options"] = OptionsJson(first.options);
  const bool with_let = first.options.HasLetKind();
  json overlaps = json::array(), overlap_sets = json::array();
  double seconds = 0.0;
  for (const EvalRun& run : runs) {
    const std::string tag = DescribeOverlaps(run.options.classes);
    overlaps.push_back(tag);
    overlap_sets.push_back(
        {{"name", tag}, {"classes", ClassesJson(run.options.classes, with_let)}});
    seconds += run.result.seconds;
  }
  j["options"]["overlaps"] = overlaps;
  j["overlap_sets"] = overlap_sets;
  j["aos_computed"] = first.result.aos_computed;
  j["seconds"] = seconds;
  const ScoreSummary& sc = first.result.scores;
  j["scores"] = {{"num_scores", sc.num_scores},
                 {"num_outside_unit", sc.num_outside_unit},
                 {"min", sc.min_score},
                 {"max", sc.max_score},
                 {"transform", ScoreTransformName(first.options.score_transform)},
                 {"probability_metrics", first.result.probability_metrics}};
  j["small_sample_labels"] = kSmallSampleLabels;
  j["notes"] = EvalNotes(runs);
  json results = json::array();
  for (const EvalRun& run : runs) {
    const std::string tag = DescribeOverlaps(run.options.classes);
    for (size_t c = 0; c < run.result.results.size(); ++c) {
      results.push_back(ClassResultJson(run.result.results[c], tag, RunSuffix(runs, run)));
      if (run.errors && c < run.errors->size()) {
        const ErrorAnalysis& a = (*run.errors)[c];
        const ClassResult& r = run.result.results[c];
        // AnalyzeAllErrors' cells are Evaluate's, in its order: checked all the same.
        if (r.evaluated && a.class_name == r.class_name && a.kind == r.metric &&
            a.difficulty == r.difficulty) {
          results.back()["errors"] = ErrorAnalysisJson(a);
        }
      }
      if (run.bootstrap && c < run.bootstrap->cells.size()) {
        const BootstrapCell& cell = run.bootstrap->cells[c];
        json& entry = results.back();
        entry["bootstrap"] = BootstrapCellJson(cell, run.options.matcher);
        // Each breakdown bin's intervals beside its figures (the same bins, in the same order).
        if (entry.contains("breakdown") && entry["breakdown"].size() == cell.breakdown.size()) {
          for (size_t k = 0; k < cell.breakdown.size(); ++k) {
            entry["breakdown"][k]["bootstrap"] =
                BootstrapBinJson(cell.breakdown[k], run.options.matcher);
          }
        }
      }
    }
  }
  if (first.bootstrap) j["bootstrap"] = BootstrapSummaryJson(*first.bootstrap);
  if (first.errors) {
    double error_seconds = 0.0;
    for (const EvalRun& run : runs) {
      if (!run.errors) continue;
      for (const ErrorAnalysis& a : *run.errors) error_seconds += a.seconds;
    }
    j["error_analysis"] = {
        {"background_overlap", first.errors->empty() ? ErrorAnalysisOptions().background_overlap
                                                     : first.errors->front().background_overlap},
        {"seconds", error_seconds}};
  }
  j["results"] = results;
  return j;
}

json EvalResultToJson(const EvalResult& result, const EvalOptions& options,
                      const EvalRunInfo& info) {
  return EvalResultToJson(OneRun(result, options), info);
}

int64_t WriteMatchRecordsCsv(const std::filesystem::path& path, const EvalResult& result,
                             const std::vector<EvalFrame>& frames) {
  AtomicPath out(path);
  std::FILE* file = std::fopen(out.temp_path().c_str(), "wb");
  STEREODET_CHECK_IO(file != nullptr) << "cannot write " << path.string();
  fmt::memory_buffer buf;
  auto flush = [&](bool force) {
    if (!force && buf.size() < (1 << 20)) return;
    const size_t n = std::fwrite(buf.data(), 1, buf.size(), file);
    const bool ok = n == buf.size();
    buf.clear();
    if (!ok) {
      std::fclose(file);
      STEREODET_THROW_IO() << "cannot write " << path.string();
    }
  };
  auto out_it = std::back_inserter(buf);
  fmt::format_to(out_it,
                 "frame,class,metric,difficulty,min_overlap,outcome,detection,label,score,iou,"
                 "det_type,det_height_px,det_width_px,det_distance_m,label_type,label_height_px,"
                 "label_width_px,label_distance_m,label_occluded,label_truncated,"
                 "label_difficulty,label_valid\n");
  int64_t rows = 0;
  for (const ClassResult& r : result.results) {
    for (const MatchRecord& m : r.records) {
      STEREODET_CHECK(m.frame >= 0 && static_cast<size_t>(m.frame) < frames.size())
          << "match record of frame " << m.frame << " outside the " << frames.size() << " frames";
      const EvalFrame& f = frames[m.frame];
      fmt::format_to(out_it, "{},{},{},{},{},{},{},{},", f.id, r.class_name,
                     OverlapKindName(r.metric), DifficultyName(r.difficulty), r.min_overlap,
                     OutcomeName(m.outcome), m.detection, m.label);
      if (m.detection >= 0) {
        fmt::format_to(out_it, "{}", f.detections[m.detection].score.value_or(NAN));
      }
      fmt::format_to(out_it, ",{},", m.iou);
      if (m.detection >= 0) {
        const Object& d = f.detections[m.detection];
        fmt::format_to(out_it, "{},{:.6g},{:.6g},{},", d.type, d.box.Height(), d.box.Width(),
                       d.Has3D() ? fmt::format("{}", d.box3d.location.z()) : std::string());
      } else {
        fmt::format_to(out_it, ",,,,");
      }
      if (m.label >= 0) {
        const Object& l = f.labels[m.label];
        const std::optional<Difficulty> easiest = EasiestDifficulty(l);
        fmt::format_to(
            out_it, "{},{:.6g},{:.6g},{},{},{},{},{}\n", l.type, l.box.Height(), l.box.Width(),
            l.Has3D() ? fmt::format("{}", l.box3d.location.z()) : std::string(), l.occluded,
            l.truncated, easiest ? DifficultyName(*easiest) : "", m.label_valid ? 1 : 0);
      } else {
        fmt::format_to(out_it, ",,,,,,,\n");
      }
      ++rows;
      flush(false);
    }
  }
  flush(true);
  STEREODET_CHECK_IO(std::fclose(file) == 0) << "cannot write " << path.string();
  out.Commit();
  return rows;
}

namespace {

// Csv(v) written at `out` (fmt's text, WriteFmtShortest: the same bytes at half fmt's cost).
char* WriteCsv(char* out, double v) { return std::isnan(v) ? out : WriteFmtShortest(out, v); }

char* WriteInt(char* out, int64_t v) { return std::to_chars(out, out + 24, v).ptr; }

// WriteCsv with the text of the last value written kept: a value with the same bits as the last
// one is copied instead of formatted again. On an exact curve recall repeats on most points (a FP
// moves only precision and FP per frame) and FP per frame on a quarter of them.
class CachedCsv {
 public:
  char* Write(char* out, double v) {
    const uint64_t bits = std::bit_cast<uint64_t>(v);
    if (!valid_ || bits != bits_) {
      length_ = static_cast<int>(WriteCsv(text_, v) - text_);
      bits_ = bits;
      valid_ = true;
    }
    std::memcpy(out, text_, kFmtShortestMaxChars);  // fixed size: a few moves (room: see below)
    return out + length_;
  }

 private:
  char text_[kFmtShortestMaxChars];
  uint64_t bits_ = 0;
  int length_ = 0;
  bool valid_ = false;
};

// PrCsv's and RocCsv's text of `curve` appended to `pr` and `roc` (either may be null) in one pass:
// an exact curve is tens of thousands of rows, and the ROC's five columns are the PR's, so each
// number is formatted once, into the PR row, and copied from there.
void AppendCurveCsvs(const std::vector<CurvePoint>& curve, int64_t num_frames, bool with_aos,
                     std::string* pr, std::string* roc) {
  if (pr) {
    pr->reserve(pr->size() + 128 * (curve.size() + 1));  // a row is about 110 bytes
    pr->append("threshold,tp,fp,fn,precision,recall,fp_per_frame");
    pr->append(with_aos ? ",orientation\n" : "\n");
  }
  if (roc) {
    roc->reserve(roc->size() + 96 * (curve.size() + 1));  // about 75
    roc->append("fp_per_frame,recall,threshold,tp,fp\n");
  }
  // A row has 5 numbers of at most kFmtShortestMaxChars and 3 counts of at most 20 characters
  // (CachedCsv copies kFmtShortestMaxChars bytes whatever the length: the room is counted so).
  char row[8 * kFmtShortestMaxChars + 16];
  CachedCsv recall_text, fp_per_frame_text;
  // The curve is in descending threshold order, so FP per frame ascends.
  for (const CurvePoint& p : curve) {
    char* it = WriteCsv(row, p.threshold);
    char* const tp = it + 1;  // tp,fp
    *it++ = ',';
    it = WriteInt(it, p.tp);
    *it++ = ',';
    it = WriteInt(it, p.fp);
    char* const tp_end = it;
    *it++ = ',';
    it = WriteInt(it, p.fn);
    *it++ = ',';
    it = WriteCsv(it, p.precision);
    *it++ = ',';
    char* const recall = it;
    it = recall_text.Write(it, p.recall);
    *it++ = ',';
    char* const fp_per_frame = it;
    it = fp_per_frame_text.Write(it, FpPerFrame(p, num_frames));
    char* const fp_per_frame_end = it;
    if (with_aos) {
      *it++ = ',';
      it = WriteCsv(it, p.orientation);
    }
    *it++ = '\n';
    if (pr) pr->append(row, static_cast<size_t>(it - row));
    if (roc) {
      roc->append(fp_per_frame, fp_per_frame_end).push_back(',');
      roc->append(recall, fp_per_frame - 1).push_back(',');  // recall
      roc->append(row, tp - 1);                              // threshold
      roc->append(tp - 1, tp_end).push_back('\n');           // ,tp,fp
    }
  }
}

}  // namespace

std::string PrCsv(const std::vector<CurvePoint>& curve, int64_t num_frames, bool with_aos) {
  std::string pr;
  AppendCurveCsvs(curve, num_frames, with_aos, &pr, nullptr);
  return pr;
}

std::string RocCsv(const std::vector<CurvePoint>& curve, int64_t num_frames) {
  std::string roc;
  AppendCurveCsvs(curve, num_frames, false, nullptr, &roc);
  return roc;
}

std::vector<std::filesystem::path> WriteEvalReport(const std::filesystem::path& out_dir,
                                                   const std::vector<EvalRun>& runs,
                                                   const EvalRunInfo& info) {
  std::vector<std::filesystem::path> written;
  auto write = [&](const std::filesystem::path& path, const std::string& text) {
    WriteFileAtomically(path, text);
    written.push_back(path);
  };
  write(out_dir / "results.json", EvalResultToJson(runs, info).dump(1) + "\n");

  std::ostringstream summary;
  summary << "class,metric,difficulty,min_overlap,evaluated,num_valid_labels,num_detections,ap_r40,"
             "ap_r11,ap_voc,aos_r40,aos_r11,apl_r40,apl_r11,threshold,tp,fp,fn,precision,recall,f1,"
             "best_f1_threshold,"
             "best_f1,brier_labels,brier_detections,brier_all,ece,dece,overlaps\n";
  for (const EvalRun& run : runs) {
    const std::string tag = DescribeOverlaps(run.options.classes);
    for (const ClassResult& r : run.result.results) {
      summary << r.class_name << ',' << OverlapKindName(r.metric) << ','
              << DifficultyName(r.difficulty) << ',' << r.min_overlap << ','
              << (r.evaluated ? 1 : 0);
      if (!r.evaluated) {
        summary << std::string(23, ',') << ',' << tag << '\n';
        continue;
      }
      const OperatingPoint& op = r.at_threshold;
      summary << ',' << r.num_valid_labels << ',' << r.num_detections << ',' << Csv(r.ap_r40) << ','
              << Csv(r.ap_r11) << ',' << Csv(r.ap_voc) << ',' << Csv(r.aos_r40) << ','
              << Csv(r.aos_r11) << ',' << Csv(r.apl_r40) << ',' << Csv(r.apl_r11) << ','
              << Csv(op.threshold) << ',' << op.tp << ',' << op.fp << ',' << op.fn << ','
              << Csv(op.precision) << ',' << Csv(op.recall) << ',' << Csv(op.f1) << ','
              << Csv(r.best_f1.threshold) << ',' << Csv(r.best_f1.f1) << ','
              << Csv(r.brier.over_labels) << ',' << Csv(r.brier.over_detections) << ','
              << Csv(r.brier.over_all) << ',' << Csv(r.calibration.ece) << ','
              << Csv(r.calibration.dece) << ',' << tag << '\n';
    }
  }
  write(out_dir / "summary.csv", summary.str());

  // errors.csv: with `eval --errors`, every cell's error types and their dAP.
  std::string errors;
  for (const EvalRun& run : runs) {
    if (!run.errors) continue;
    errors += FormatErrorCsv(*run.errors, DescribeOverlaps(run.options.classes), errors.empty());
  }
  if (!errors.empty()) write(out_dir / "errors.csv", errors);

  // breakdown.csv: one row per cell and bin, when a run has breakdowns (the bins' figures would
  // repeat summary.csv's keys there).
  std::ostringstream breakdown;
  bool any_breakdown = false;
  // The naive_* columns: the bin evaluated on its own (eval --breakdown-naive), empty without it.
  breakdown << "class,metric,difficulty,axis,lower,upper,num_valid_labels,ap_r40,ap_r11,ap_voc,"
               "threshold,tp,fp,fn,precision,recall,brier_labels,brier_detections,brier_all,"
               "naive_num_valid_labels,naive_ap_r40,naive_tp,naive_fp,naive_fn,naive_precision,"
               "naive_recall,overlaps\n";
  for (const EvalRun& run : runs) {
    const std::string tag = DescribeOverlaps(run.options.classes);
    for (const ClassResult& r : run.result.results) {
      for (const BreakdownBin& b : r.breakdown) {
        any_breakdown = true;
        const OperatingPoint& op = b.at_threshold;
        breakdown << r.class_name << ',' << OverlapKindName(r.metric) << ','
                  << DifficultyName(r.difficulty) << ',' << BreakdownAxisName(b.axis) << ','
                  << Csv(b.lower) << ',' << Csv(b.upper) << ',' << b.num_valid_labels << ','
                  << Csv(b.curve.ap_r40) << ',' << Csv(b.curve.ap_r11) << ',' << Csv(b.curve.ap_voc)
                  << ',' << Csv(op.threshold) << ',' << op.tp << ',' << op.fp << ',' << op.fn << ','
                  << Csv(op.precision) << ',' << Csv(op.recall) << ',' << Csv(b.brier.over_labels)
                  << ',' << Csv(b.brier.over_detections) << ',' << Csv(b.brier.over_all) << ',';
        if (b.naive) {
          const OperatingPoint& nop = b.naive->at_threshold;
          breakdown << b.naive->num_valid_labels << ',' << Csv(b.naive->curve.ap_r40) << ','
                    << nop.tp << ',' << nop.fp << ',' << nop.fn << ',' << Csv(nop.precision) << ','
                    << Csv(nop.recall) << ',';
        } else {
          breakdown << ",,,,,,,";
        }
        breakdown << tag << '\n';
      }
    }
  }
  if (any_breakdown) write(out_dir / "breakdown.csv", breakdown.str());

  for (const EvalRun& run : runs) {
    const EvalResult& result = run.result;
    const std::string suffix = RunSuffix(runs, run);
    for (const ClassResult& r : result.results) {
      if (!r.evaluated) continue;
      const std::string stem = CurveStem(r) + suffix;
      // The names results.json gives (ClassResultJson).
      std::string pr, roc;
      AppendCurveCsvs(r.curve, result.num_frames, r.has_aos, &pr, &roc);
      write(out_dir / CurveFile("pr_", r, suffix), pr);
      write(out_dir / CurveFile("roc_", r, suffix), roc);
      if (r.filtered) {
        write(out_dir / CurveFile("pr_naive_", r, suffix),
              PrCsv(r.filtered->naive_curve.curve, result.num_frames, r.has_aos));
        write(out_dir / CurveFile("pr_stable_", r, suffix),
              PrCsv(r.filtered->stable_curve.curve, result.num_frames, r.has_aos));
      }
      std::ostringstream rel;
      rel << "lower,upper,count,mean_score,tp_fraction\n";
      for (const ReliabilityBin& b : r.calibration.bins) {
        rel << Csv(b.lower) << ',' << Csv(b.upper) << ',' << b.count << ',' << Csv(b.mean_score)
            << ',' << Csv(b.tp_fraction) << '\n';
      }
      write(out_dir / "curves" / ("reliability_" + stem + ".csv"), rel.str());
      std::ostringstream loc;
      loc << "lower_m,upper_m,count,centre_error_mean_m,centre_error_median_m,centre_error_p90_m,"
             "depth_error_mean_m,abs_depth_error_mean_m,abs_depth_error_median_m,"
             "abs_depth_error_p90_m\n";
      for (const DistanceBin& b : r.localization) {
        loc << Csv(b.lower_m) << ',' << Csv(b.upper_m) << ',' << b.count << ','
            << Csv(b.centre_error_mean_m) << ',' << Csv(b.centre_error_median_m) << ','
            << Csv(b.centre_error_p90_m) << ',' << Csv(b.depth_error_mean_m) << ','
            << Csv(b.abs_depth_error_mean_m) << ',' << Csv(b.abs_depth_error_median_m) << ','
            << Csv(b.abs_depth_error_p90_m) << '\n';
      }
      write(out_dir / "curves" / ("localization_" + stem + ".csv"), loc.str());
    }
  }
  return written;
}

std::vector<std::filesystem::path> WriteEvalReport(const std::filesystem::path& out_dir,
                                                   const EvalResult& result,
                                                   const EvalOptions& options,
                                                   const EvalRunInfo& info) {
  return WriteEvalReport(out_dir, OneRun(result, options), info);
}

namespace {

void FormatRun(const EvalResult& result, const EvalOptions& options, std::ostringstream& out) {
  out << fmt::format("matcher {}, {} frames, overlaps {}", MatcherName(options.matcher),
                     result.num_frames, DescribeOverlaps(options.classes));
  if (!options.filter.empty()) out << ", filter " << FilterModeName(options.filter.mode);
  out << "\n";
  std::string diff_header;
  for (Difficulty d : options.difficulties) diff_header += fmt::format(" {:>8}", DifficultyName(d));
  // The kind column fits its longest name ("let-bev"), 4 wide without a LET kind.
  size_t kind_width = 4;
  for (OverlapKind kind : options.metrics) {
    kind_width = std::max(kind_width, std::string_view(OverlapKindName(kind)).size());
  }
  out << fmt::format("{:<12} {:<{}} {:>5} | {:<7}{} |", "class", "kind", kind_width, "tau", "",
                     diff_header);
  // The operating point is shown at Moderate (KITTI's ranking level) when evaluated.
  Difficulty op_difficulty = options.difficulties.front();
  for (Difficulty d : options.difficulties) {
    if (d == Difficulty::kModerate) op_difficulty = d;
  }
  out << "  (operating point at " << DifficultyName(op_difficulty) << ")\n";
  // The small-sample mark explains the KITTI matcher's AP_R40 cap; other matchers are exact.
  const bool mark_small = options.matcher == Matcher::kKitti;
  for (const ClassSpec& spec : options.classes) {
    for (OverlapKind kind : options.metrics) {
      const ClassResult* first = result.Find(spec.name, kind, op_difficulty);
      if (!first) continue;
      if (!first->evaluated) {
        out << fmt::format(
            "{:<12} {:<{}} {:>5.2f} | not evaluated (no detection of this class with a "
            "valid {} box)\n",
            spec.name, OverlapKindName(kind), kind_width, first->min_overlap,
            OverlapKindName(PlainKind(kind)));
        continue;
      }
      auto cells = [&](auto format) {
        std::string text;
        for (Difficulty d : options.difficulties) {
          const ClassResult* r = result.Find(spec.name, kind, d);
          text += fmt::format(" {:>8}", r ? format(*r) : std::string("-"));
        }
        return text;
      };
      auto line = [&](const char* what, const std::string& text) {
        return fmt::format("{:<12} {:<{}} {:>5.2f} | {:<7}{} |", spec.name, OverlapKindName(kind),
                           kind_width, first->min_overlap, what, text);
      };
      auto row = [&](const char* what, auto get, bool with_op, int decimals = 2) {
        out << line(what,
                    cells([&](const ClassResult& r) { return FormatNumber(get(r), decimals); }));
        if (with_op) {
          const OperatingPoint& op = first->at_threshold;
          out << fmt::format(
              "  TP {} FP {} FN {}  P {:.4f} R {:.4f} F1 {:.4f}  best F1 {:.4f} @ {:.4g}", op.tp,
              op.fp, op.fn, op.precision, op.recall, op.f1, first->best_f1.f1,
              first->best_f1.threshold);
        }
        out << "\n";
      };
      row(
          "AP_R40", [](const ClassResult& r) { return r.ap_r40; }, true);
      row(
          "AP_R11", [](const ClassResult& r) { return r.ap_r11; }, false);
      if (options.matcher != Matcher::kKitti)
        row(
            "AP_VOC", [](const ClassResult& r) { return r.ap_voc; }, false);
      if (first->has_aos) {
        row(
            "AOS_R40", [](const ClassResult& r) { return r.aos_r40; }, false);
        row(
            "AOS_R11", [](const ClassResult& r) { return r.aos_r11; }, false);
      }
      if (first->has_apl) {
        row(
            "APL_R40", [](const ClassResult& r) { return r.apl_r40; }, false);
        row(
            "APL_R11", [](const ClassResult& r) { return r.apl_r11; }, false);
      }
      out << line("labels", cells([&](const ClassResult& r) {
                    return std::to_string(r.num_valid_labels) +
                           (mark_small && IsSmallSample(r) ? "*" : "");
                  }))
          << "\n";
      auto brier = [](const ClassResult& r) { return r.brier.over_labels; };
      auto ece = [](const ClassResult& r) { return r.calibration.ece; };
      row("Brier_L", brier, false, 4);
      row("ECE", ece, false, 4);
      row(
          "D-ECE", [](const ClassResult& r) { return r.calibration.dece; }, false, 4);
      if (first->filtered) {
        const FilteredStats& fs = *first->filtered;
        out << fmt::format(
            "{:<12} {:<{}} {:>5} | filtered: naive TP {} FP {} FN {} P {:.4f} R {:.4f}; "
            "stable TP {} FP {} FN {} P {:.4f} R {:.4f}\n",
            "", "", kind_width, "", fs.naive.tp, fs.naive.fp, fs.naive.fn, fs.naive.precision,
            fs.naive.recall, fs.stable.tp, fs.stable.fp, fs.stable.fn, fs.stable.precision,
            fs.stable.recall);
        out << fmt::format("{:<12} {:<{}} {:>5} | filtered AP_R40: naive {}, stable {}\n", "", "",
                           kind_width, "", FormatNumber(fs.naive_curve.ap_r40, 2),
                           FormatNumber(fs.stable_curve.ap_r40, 2));
      }
      // Breakdowns: AP_R40 per difficulty, then the operating point and Brier at the operating
      // point's difficulty.
      for (size_t k = 0; k < first->breakdown.size(); ++k) {
        const BreakdownBin& bin = first->breakdown[k];
        const std::string name =
            std::string(BreakdownAxisName(bin.axis)) + " " + BreakdownBinName(bin.lower, bin.upper);
        const std::string aps = cells([&](const ClassResult& r) {
          return k < r.breakdown.size() ? FormatNumber(r.breakdown[k].curve.ap_r40, 2)
                                        : std::string("-");
        });
        const OperatingPoint& op = bin.at_threshold;
        out << fmt::format("{:>23} | {:<7}{} |  labels {}  TP {} FP {} FN {}  Brier_L {}\n", name,
                           "AP_R40", aps, bin.num_valid_labels, op.tp, op.fp, op.fn,
                           FormatNumber(bin.brier.over_labels, 4));
        if (bin.naive) {
          // The naive recomputation's line under the stable one.
          const std::string naive_aps = cells([&](const ClassResult& r) {
            return k < r.breakdown.size() && r.breakdown[k].naive
                       ? FormatNumber(r.breakdown[k].naive->curve.ap_r40, 2)
                       : std::string("-");
          });
          const OperatingPoint& nop = bin.naive->at_threshold;
          out << fmt::format("{:>23} | {:<7}{} |  labels {}  TP {} FP {} FN {}\n", "naive",
                             "AP_R40", naive_aps, bin.naive->num_valid_labels, nop.tp, nop.fp,
                             nop.fn);
        }
      }
    }
  }
}

}  // namespace

std::string FormatEvalTable(const std::vector<EvalRun>& runs) {
  std::ostringstream out;
  for (size_t k = 0; k < runs.size(); ++k) {
    if (k > 0) out << "\n";
    FormatRun(runs[k].result, runs[k].options, out);
    if (runs[k].bootstrap) out << FormatBootstrapTable(*runs[k].bootstrap);
    if (runs[k].errors) out << FormatErrorTable(*runs[k].errors);
  }
  for (const std::string& note : EvalNotes(runs)) out << note << "\n";
  return out.str();
}

std::string FormatEvalTable(const EvalResult& result, const EvalOptions& options) {
  return FormatEvalTable(OneRun(result, options));
}

std::string FormatSweepCsv(const std::vector<SweepRow>& rows, FilterBound bound) {
  std::ostringstream out;
  out << "class,metric,difficulty,filter,value,naive_tp,naive_fp,naive_fn,naive_precision,naive_"
         "recall,"
         "stable_tp,stable_fp,stable_fn,stable_precision,stable_recall\n";
  for (const SweepRow& r : rows) {
    const OperatingPoint& n = r.stats.naive;
    const OperatingPoint& s = r.stats.stable;
    out << r.class_name << ',' << OverlapKindName(r.metric) << ',' << DifficultyName(r.difficulty)
        << ',' << FilterBoundName(bound) << ',' << Csv(r.value) << ',' << n.tp << ',' << n.fp << ','
        << n.fn << ',' << Csv(n.precision) << ',' << Csv(n.recall) << ',' << s.tp << ',' << s.fp
        << ',' << s.fn << ',' << Csv(s.precision) << ',' << Csv(s.recall) << '\n';
  }
  return out.str();
}

std::string FormatCompareCsv(const std::vector<CompareRow>& rows) {
  std::string csv =
      "class,metric,difficulty,lower_m,upper_m,count_a,abs_dz_mean_a,count_b,abs_dz_mean_b,"
      "difference_b_minus_a,centre_error_mean_a,centre_error_mean_b,model_dz,"
      "difference_a_minus_b\n";
  for (const CompareRow& r : rows) {
    // difference_a_minus_b (the sign issue 13 words the figure in) is appended, so that readers of
    // the earlier columns, by name or by position, read what they read before.
    csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.class_name,
                       OverlapKindName(r.metric), DifficultyName(r.difficulty), r.lower_m,
                       r.upper_m, r.count_a, Csv(r.abs_depth_error_mean_a_m), r.count_b,
                       Csv(r.abs_depth_error_mean_b_m), Csv(r.difference_b_minus_a_m),
                       Csv(r.centre_error_mean_a_m), Csv(r.centre_error_mean_b_m),
                       Csv(r.model_depth_error_m), Csv(0.0 - r.difference_b_minus_a_m));
  }
  return csv;
}

std::string FormatCompareTable(const std::vector<CompareRow>& rows) {
  std::string text;
  for (size_t k = 0; k < rows.size(); ++k) {
    const CompareRow& r = rows[k];
    if (k == 0 || rows[k - 1].class_name != r.class_name || rows[k - 1].metric != r.metric ||
        rows[k - 1].difficulty != r.difficulty) {
      text += fmt::format("\n{} {} {}: mean |depth error| of matched pairs (m)\n", r.class_name,
                          OverlapKindName(r.metric), DifficultyName(r.difficulty));
      text += fmt::format("  {:>11} {:>7} {:>8} {:>7} {:>8} {:>8} {:>8}\n", "depth", "n A", "A",
                          "n B", "B", "B - A", "model");
    }
    text += fmt::format("  {:>4g}-{:<4g} m {:>7} {:>8} {:>7} {:>8} {:>8} {:>8.3f}\n", r.lower_m,
                        r.upper_m, r.count_a, FormatNumber(r.abs_depth_error_mean_a_m, 3),
                        r.count_b, FormatNumber(r.abs_depth_error_mean_b_m, 3),
                        FormatNumber(r.difference_b_minus_a_m, 3), r.model_depth_error_m);
  }
  return text;
}

}  // namespace stereodet
