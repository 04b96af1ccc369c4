// stereodet._core's COCO mode: the text of a COCO ground-truth file and of a results file in,
// COCOeval's numbers out (eval/coco.h: EvaluateCoco, pycocotools-exact). stereodet.coco (the
// pure-Python module) turns paths, dicts and pycocotools' COCO objects into that text.
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "common.h"
#include "stereodet/eval/coco.h"
#include "stereodet/eval/coco_bootstrap.h"
#include "stereodet/pipelines/coco_evaluation.h"
#include "stereodet/util/check.h"

namespace stereodet::python {
namespace {

// A numpy array of `shape` holding `values` (row-major, as EvaluateCoco lays its arrays out).
py::array_t<double> Shaped(const std::vector<double>& values, std::vector<py::ssize_t> shape) {
  py::array_t<double> out(shape);
  std::copy(values.begin(), values.end(), out.mutable_data());
  return out;
}

py::dict CocoEvaluate(const std::string& gt_text, const std::string& gt_source,
                      const std::string& dt_text, const std::string& dt_source,
                      bool honor_ignore_flag, std::vector<int> max_dets, int num_threads,
                      const std::string& matcher, bool score_metrics, double score_threshold,
                      const std::string& score_transform, int calibration_bins, int bootstrap,
                      uint64_t bootstrap_seed, double bootstrap_confidence,
                      const std::string& bootstrap_method,
                      const std::optional<std::string>& dt_b_text, const std::string& dt_b_source,
                      const std::string& area_ranges) {
  CocoEvalResult result;
  std::optional<CocoEvalResult> result_b;
  std::optional<CocoBootstrapResult> intervals;
  std::optional<CocoPairedBootstrapResult> paired;
  std::string summary;
  {
    ReleaseGil release;
    const CocoGroundTruth gt = ParseCocoGroundTruth(gt_text, gt_source);
    const std::vector<CocoDetection> dets = ParseCocoDetections(dt_text, dt_source, gt);
    std::vector<CocoDetection> dets_b;
    if (dt_b_text) dets_b = ParseCocoDetections(*dt_b_text, dt_b_source, gt);
    CocoEvalOptions options;
    options.honor_ignore_flag = honor_ignore_flag;
    options.max_dets = std::move(max_dets);
    options.num_threads = num_threads;
    const auto parsed_matcher = ParseCocoMatcher(matcher);
    STEREODET_CHECK(parsed_matcher.has_value())
        << "matcher: COCO mode has 'coco' (pycocotools' greedy one) and 'optimal', got '" << matcher
        << "'";
    options.matcher = *parsed_matcher;
    const auto transform = ParseScoreTransform(score_transform);
    STEREODET_CHECK(transform.has_value())
        << "score_transform: 'none' or 'sigmoid', got '" << score_transform << "'";
    STEREODET_CHECK(area_ranges == "pycocotools" || area_ranges == "stable")
        << "area_ranges: 'pycocotools' (each range matched on its own) or 'stable' (every range "
           "counted from the matching of range all), got '"
        << area_ranges << "'";
    options.stable_area_ranges = area_ranges == "stable";
    options.score_metrics = score_metrics;
    options.score_threshold = score_threshold;
    options.score_transform = *transform;
    options.calibration_bins = calibration_bins;
    options.Check();
    BootstrapOptions resampling;
    resampling.num_resamples = bootstrap;
    resampling.seed = bootstrap_seed;
    resampling.confidence = bootstrap_confidence;
    const auto method = ParseBootstrapMethod(bootstrap_method);
    STEREODET_CHECK(method.has_value())
        << "bootstrap_method: 'percentile' or 'bca', got '" << bootstrap_method << "'";
    resampling.method = *method;
    resampling.keep_samples = true;
    resampling.num_threads = num_threads;
    if (bootstrap > 0) resampling.Check();
    // Each evaluation once: the bootstraps hand over the evaluations they resample.
    if (bootstrap > 0 && dt_b_text) {
      result_b.emplace();
      paired = PairedBootstrapCoco(gt, dets, dets_b, options, resampling, &result, &*result_b);
    } else if (bootstrap > 0) {
      intervals = BootstrapCoco(gt, dets, options, resampling, &result);
    } else {
      result = EvaluateCoco(gt, dets, options);
      if (dt_b_text) result_b = EvaluateCoco(gt, dets_b, options);
    }
    summary = FormatCocoSummary(result);
  }
  const auto t = static_cast<py::ssize_t>(result.options.iou_thresholds.size());
  const auto r = static_cast<py::ssize_t>(result.options.recall_thresholds.size());
  const auto k = static_cast<py::ssize_t>(result.category_ids.size());
  const auto a = static_cast<py::ssize_t>(result.options.area_ranges.size());
  const auto m = static_cast<py::ssize_t>(result.options.max_dets.size());
  py::dict out;
  out["stats"] =
      Shaped(std::vector<double>(result.stats.begin(), result.stats.end()), {kNumCocoStats});
  out["precision"] = Shaped(result.precision, {t, r, k, a, m});
  std::vector<double> category_stats;
  for (const auto& stats : result.category_stats) {
    category_stats.insert(category_stats.end(), stats.begin(), stats.end());
  }
  out["category_stats"] = Shaped(category_stats, {k, kNumCocoStats});
  out["recall"] = Shaped(result.recall, {t, k, a, m});
  out["scores"] = Shaped(result.scores, {t, r, k, a, m});
  out["image_ids"] = result.image_ids;
  out["category_ids"] = result.category_ids;
  out["category_names"] = result.category_names;
  out["iou_thresholds"] = result.options.iou_thresholds;
  out["recall_thresholds"] = result.options.recall_thresholds;
  out["max_dets"] = result.options.max_dets;
  std::vector<std::string> area_labels;
  for (const CocoAreaRange& range : result.options.area_ranges) area_labels.push_back(range.label);
  out["area_ranges"] = area_labels;
  out["summary"] = summary;
  out["num_gt"] = result.num_gt;
  out["num_gt_skipped"] = result.num_gt_skipped;
  out["num_detections"] = result.num_detections;
  out["num_detections_skipped"] = result.num_detections_skipped;
  out["seconds"] = result.seconds;
  out["matcher"] = CocoMatcherName(result.options.matcher);
  // Intervals by summary name: {"AP": (estimate, lower, upper), ...} and every resample's values
  // ((num_resamples, 12), NaN where undefined).
  auto interval_dict = [](const CocoBootstrapResult& b) {
    py::dict d;
    std::vector<double> samples(static_cast<size_t>(b.num_resamples) * kNumCocoStats);
    for (int s = 0; s < kNumCocoScoreStats; ++s) {
      const BootstrapInterval& i = b.score_stats[s];
      if (!std::isnan(i.estimate)) {
        d[CocoScoreStatNames()[s]] = py::make_tuple(i.estimate, i.lower, i.upper);
      }
    }
    for (int s = 0; s < kNumCocoStats; ++s) {
      const BootstrapInterval& i = b.stats[s];
      d[CocoStatNames()[s]] = py::make_tuple(i.estimate, i.lower, i.upper);
      for (int r = 0; r < b.num_resamples; ++r) samples[r * kNumCocoStats + s] = i.samples[r];
    }
    py::dict out;
    out["intervals"] = d;
    out["samples"] = Shaped(samples, {b.num_resamples, kNumCocoStats});
    out["num_resamples"] = b.num_resamples;
    out["seed"] = b.seed;
    out["confidence"] = b.confidence;
    out["method"] = BootstrapMethodName(b.method);
    out["seconds"] = b.seconds;
    return out;
  };
  if (intervals) out["bootstrap"] = interval_dict(*intervals);
  if (paired) {
    out["bootstrap"] = interval_dict(paired->a);
    out["bootstrap_b"] = interval_dict(paired->b);
    out["bootstrap_difference"] = interval_dict(paired->difference);
  }
  if (result_b) {
    out["stats_b"] = Shaped(std::vector<double>(result_b->stats.begin(), result_b->stats.end()),
                            {kNumCocoStats});
  }
  if (result.options.score_metrics) {
    out["score_stats"] =
        Shaped(std::vector<double>(result.score_stats.begin(), result.score_stats.end()),
               {kNumCocoScoreStats});
    out["score_stat_names"] =
        std::vector<std::string>(CocoScoreStatNames().begin(), CocoScoreStatNames().end());
    out["probability_metrics"] = result.probability_metrics;
    // The cells as (T, K, A) arrays, one per figure.
    const size_t n = result.cells.size();
    std::vector<double> num_valid_gt(n), tp(n), fp(n), fn(n), brier_labels(n), brier_detections(n),
        brier_all(n), ece(n);
    for (size_t i = 0; i < n; ++i) {
      const CocoCell& c = result.cells[i];
      num_valid_gt[i] = static_cast<double>(c.num_valid_gt);
      tp[i] = static_cast<double>(c.at_threshold.tp);
      fp[i] = static_cast<double>(c.at_threshold.fp);
      fn[i] = static_cast<double>(c.at_threshold.fn);
      brier_labels[i] = c.brier.over_labels;
      brier_detections[i] = c.brier.over_detections;
      brier_all[i] = c.brier.over_all;
      ece[i] = c.calibration.ece;
    }
    py::dict cells;
    cells["num_valid_gt"] = Shaped(num_valid_gt, {t, k, a});
    cells["tp"] = Shaped(tp, {t, k, a});
    cells["fp"] = Shaped(fp, {t, k, a});
    cells["fn"] = Shaped(fn, {t, k, a});
    cells["brier_labels"] = Shaped(brier_labels, {t, k, a});
    cells["brier_detections"] = Shaped(brier_detections, {t, k, a});
    cells["brier_all"] = Shaped(brier_all, {t, k, a});
    cells["ece"] = Shaped(ece, {t, k, a});
    out["cells"] = cells;
  }
  return out;
}

}  // namespace

void BindCoco(py::module_& m) {
  m.def(
      "_coco_evaluate", &CocoEvaluate, py::arg("gt_text"), py::arg("gt_source"), py::arg("dt_text"),
      py::arg("dt_source"), py::arg("honor_ignore_flag") = false,
      py::arg("max_dets") = std::vector<int>{1, 10, 100}, py::arg("num_threads") = 0,
      py::arg("matcher") = "coco", py::arg("score_metrics") = false,
      py::arg("score_threshold") = -std::numeric_limits<double>::infinity(),
      py::arg("score_transform") = "none", py::arg("calibration_bins") = 10,
      py::arg("bootstrap") = 0, py::arg("bootstrap_seed") = 1,
      py::arg("bootstrap_confidence") = 0.95, py::arg("bootstrap_method") = "percentile",
      py::arg("dt_b_text") = std::nullopt, py::arg("dt_b_source") = "",
      py::arg("area_ranges") = "pycocotools",
      "COCOeval(gt, loadRes(dt), 'bbox') on the JSON texts, the GIL released: a dict of stats "
      "(12), precision (T, R, K, A, M), recall (T, K, A, M), scores, the ids and the summary "
      "text; with score_metrics, score_stats (12) and the cells' (T, K, A) arrays; with bootstrap "
      "> 0, the intervals (and with dt_b_text B's stats and the paired A - B intervals).");
}

}  // namespace stereodet::python
