#include "stereodet/pipelines/coco_evaluation.h"

#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/output_folder.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace fs = std::filesystem;

namespace {

using ordered_json = nlohmann::ordered_json;

// A float64 array in numpy's .npy format, version 1.0: the magic, a header dict padded with
// spaces to a multiple of 64 bytes, then the values in C order, little-endian.
std::string NpyFloat64(const std::vector<size_t>& shape, const std::vector<double>& values) {
  static_assert(std::endian::native == std::endian::little, "the .npy writer writes '<f8'");
  std::string dims = fmt::format("{}", fmt::join(shape, ", "));
  if (shape.size() == 1) dims += ',';  // Python's one-element tuple: (3,)
  std::string header =
      fmt::format("{{'descr': '<f8', 'fortran_order': False, 'shape': ({}), }}", dims);
  const size_t unpadded = 6 + 2 + 2 + header.size() + 1;  // magic, version, length, dict, '\n'
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::string out = "\x93NUMPY";
  out.push_back('\x01');
  out.push_back('\x00');
  out.push_back(static_cast<char>(header.size() & 0xff));
  out.push_back(static_cast<char>(header.size() >> 8));
  out += header;
  const size_t at = out.size();
  out.resize(at + values.size() * sizeof(double));
  std::memcpy(out.data() + at, values.data(), values.size() * sizeof(double));
  return out;
}

ordered_json ResultsJson(const CocoEvaluationOptions& options, const CocoEvaluationResult& run) {
  const CocoEvalResult& r = run.result;
  const CocoEvalOptions& o = r.options;
  ordered_json j;
  j["tool"] = {{"name", "stereodet eval"}, {"version", options.tool_version}};
  j["command_line"] = options.command_line;
  j["mode"] = "coco";
  j["input_hash"] = run.input_hash;
  j["input"] = {{"coco_gt", options.gt.string()},
                {"coco_det", options.det.string()},
                {"coco_det_b", options.det_b.string()},
                {"num_images", r.image_ids.size()},
                {"num_categories", r.category_ids.size()},
                {"num_gt", r.num_gt},
                {"num_gt_skipped", r.num_gt_skipped},
                {"num_detections", r.num_detections},
                {"num_detections_skipped", r.num_detections_skipped}};
  ordered_json areas = ordered_json::array();
  for (const CocoAreaRange& a : o.area_ranges) {
    areas.push_back({{"label", a.label}, {"min_area", a.min_area}, {"max_area", a.max_area}});
  }
  j["options"] = {{"iou_type", "bbox"},
                  {"iou_thresholds", o.iou_thresholds},
                  {"recall_thresholds", o.recall_thresholds},
                  {"max_dets", o.max_dets},
                  {"area_ranges", areas},
                  {"honor_ignore_flag", o.honor_ignore_flag},
                  {"area_ranges_mode", o.stable_area_ranges ? "stable" : "pycocotools"},
                  {"matcher", CocoMatcherName(o.matcher)},
                  {"score_metrics", o.score_metrics}};
  if (o.score_metrics) {
    // -inf (every detection) is written as null, as JSON has no infinity.
    j["options"]["score_threshold"] = o.score_threshold;
    j["options"]["score_transform"] = ScoreTransformName(o.score_transform);
    j["options"]["calibration_bins"] = o.calibration_bins;
  }
  j["seconds"] = r.seconds;
  j["read_seconds"] = run.read_seconds;
  ordered_json stats = ordered_json::object();
  for (int s = 0; s < kNumCocoStats; ++s) stats[CocoStatNames()[s]] = r.stats[s];
  j["stats"] = stats;
  j["categories"] = ordered_json::array();
  for (size_t k = 0; k < r.category_ids.size(); ++k) {
    // The category's own 12 numbers (COCOeval with params.catIds = [id]).
    ordered_json stats_k = ordered_json::object();
    for (int s = 0; s < kNumCocoStats; ++s) stats_k[CocoStatNames()[s]] = r.category_stats[k][s];
    j["categories"].push_back(
        {{"id", r.category_ids[k]}, {"name", r.category_names[k]}, {"stats", stats_k}});
  }
  const size_t T = o.iou_thresholds.size(), R = o.recall_thresholds.size(),
               K = r.category_ids.size(), A = o.area_ranges.size(), M = o.max_dets.size();
  j["arrays"] = {{"precision", {{"file", "precision.npy"}, {"shape", {T, R, K, A, M}}}},
                 {"recall", {{"file", "recall.npy"}, {"shape", {T, K, A, M}}}},
                 {"scores", {{"file", "scores.npy"}, {"shape", {T, R, K, A, M}}}}};
  if (o.score_metrics) {
    j["probability_metrics"] = r.probability_metrics;
    ordered_json score_stats = ordered_json::object();
    for (int s = 0; s < kNumCocoScoreStats; ++s) {
      score_stats[CocoScoreStatNames()[s]] = r.score_stats[s];
    }
    j["score_stats"] = score_stats;
    j["cells"] = {{"file", "cells.csv"}, {"reliability", "reliability.csv"}};
  }
  // One number's interval; NaN (an undefined bound) is written as null.
  auto interval = [](const BootstrapInterval& i) {
    return ordered_json{{"estimate", i.estimate},
                        {"lower", i.lower},
                        {"upper", i.upper},
                        {"num_defined", i.num_defined}};
  };
  auto intervals = [&](const CocoBootstrapResult& b) {
    ordered_json j = {{"num_resamples", b.num_resamples}, {"seed", b.seed},
                      {"confidence", b.confidence},       {"method", BootstrapMethodName(b.method)},
                      {"num_images", b.num_images},       {"seconds", b.seconds}};
    ordered_json stats = ordered_json::object();
    for (int s = 0; s < kNumCocoStats; ++s) stats[CocoStatNames()[s]] = interval(b.stats[s]);
    j["stats"] = stats;
    if (!std::isnan(b.score_stats[0].estimate)) {
      ordered_json score_stats = ordered_json::object();
      for (int s = 0; s < kNumCocoScoreStats; ++s) {
        score_stats[CocoScoreStatNames()[s]] = interval(b.score_stats[s]);
      }
      j["score_stats"] = score_stats;  // the ECE ones are not resampled: null bounds
    }
    return j;
  };
  if (run.bootstrap) j["bootstrap"] = intervals(*run.bootstrap);
  if (run.result_b) {
    ordered_json compare = {{"coco_det_b", options.det_b.string()}};
    ordered_json stats_b = ordered_json::object(), difference = ordered_json::object();
    for (int s = 0; s < kNumCocoStats; ++s) {
      const double a = r.stats[s], b = run.result_b->stats[s];
      stats_b[CocoStatNames()[s]] = b;
      difference[CocoStatNames()[s]] =
          a < 0 || b < 0 ? std::numeric_limits<double>::quiet_NaN() : a - b;
    }
    compare["stats_b"] = stats_b;
    compare["difference"] = difference;  // A - B; null where either is -1
    if (run.paired) compare["paired_bootstrap"] = intervals(run.paired->difference);
    j["compare"] = compare;
  }
  return j;
}

// One row per IoU threshold x category x area range, in CellIndex order. NaN is written "nan".
std::string CellsCsv(const CocoEvalResult& r) {
  const CocoEvalOptions& o = r.options;
  std::string csv =
      "iou,category_id,area,num_valid_gt,tp,fp,fn,precision,recall,f1,brier_labels,"
      "brier_detections,brier_all,ece,laece,num_detections\n";
  for (size_t t = 0; t < o.iou_thresholds.size(); ++t) {
    for (size_t k = 0; k < r.category_ids.size(); ++k) {
      for (size_t a = 0; a < o.area_ranges.size(); ++a) {
        const CocoCell& c =
            r.cells[r.CellIndex(static_cast<int>(t), static_cast<int>(k), static_cast<int>(a))];
        const OperatingPoint& p = c.at_threshold;
        csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", o.iou_thresholds[t],
                           r.category_ids[k], o.area_ranges[a].label, c.num_valid_gt, p.tp, p.fp,
                           p.fn, p.precision, p.recall, p.f1, c.brier.over_labels,
                           c.brier.over_detections, c.brier.over_all, c.calibration.ece,
                           c.calibration.laece, c.calibration.num_detections);
      }
    }
  }
  return csv;
}

// The reliability bins of every cell, cells in CellIndex order, bins ascending.
std::string ReliabilityCsv(const CocoEvalResult& r) {
  const CocoEvalOptions& o = r.options;
  std::string csv = "iou,category_id,area,lower,upper,count,mean_score,tp_fraction\n";
  for (size_t t = 0; t < o.iou_thresholds.size(); ++t) {
    for (size_t k = 0; k < r.category_ids.size(); ++k) {
      for (size_t a = 0; a < o.area_ranges.size(); ++a) {
        const CocoCell& c =
            r.cells[r.CellIndex(static_cast<int>(t), static_cast<int>(k), static_cast<int>(a))];
        for (const ReliabilityBin& b : c.calibration.bins) {
          csv += fmt::format("{},{},{},{},{},{},{},{}\n", o.iou_thresholds[t], r.category_ids[k],
                             o.area_ranges[a].label, b.lower, b.upper, b.count, b.mean_score,
                             b.tp_fraction);
        }
      }
    }
  }
  return csv;
}

}  // namespace

const std::array<const char*, kNumCocoStats>& CocoStatNames() {
  static const std::array<const char*, kNumCocoStats> kNames = {
      "AP", "AP50", "AP75", "APs", "APm", "APl", "AR1", "AR10", "AR100", "ARs", "ARm", "ARl"};
  return kNames;
}

void CocoEvaluationOptions::Check() const {
  STEREODET_CHECK(!gt.empty()) << "COCO evaluation: no ground-truth file (--coco-gt)";
  STEREODET_CHECK(!det.empty()) << "COCO evaluation: no results file (--coco-det)";
  eval.Check();
  if (bootstrap) bootstrap->Check();
}

std::string FormatCocoBootstrap(const CocoBootstrapResult& b) {
  std::string out = fmt::format(
      "bootstrap: {} resamples of the {} images (seed {}), {:g}% {} intervals\n", b.num_resamples,
      b.num_images, b.seed, 100 * b.confidence, BootstrapMethodTitle(b.method));
  // One number's line; an estimate of -1 has no interval, `why` says why.
  auto line = [](const char* name, const BootstrapInterval& i, const char* why) {
    return i.estimate < 0
               ? fmt::format("{:<6} -1 ({})\n", name, why)
               : fmt::format("{:<6} {:.3f} [{:.3f}, {:.3f}]\n", name, i.estimate, i.lower, i.upper);
  };
  for (int s = 0; s < kNumCocoStats; ++s) {
    out += line(CocoStatNames()[s], b.stats[s], "no ground truth");
  }
  // With --coco-brier: the Brier numbers (the ECE ones are not resampled).
  if (!std::isnan(b.score_stats[0].estimate)) {
    for (int s = 0; s < 9; ++s) out += line(CocoScoreStatNames()[s], b.score_stats[s], "undefined");
  }
  return out;
}

std::string FormatCocoCompare(const CocoEvalResult& a, const CocoEvalResult& b,
                              const CocoPairedBootstrapResult* paired) {
  std::string out =
      paired == nullptr
          ? std::string("A - B:\n")
          : fmt::format(
                "A - B, paired bootstrap: {} resamples of the {} images (seed {}), {:g}% {} "
                "intervals\n",
                paired->difference.num_resamples, paired->difference.num_images,
                paired->difference.seed, 100 * paired->difference.confidence,
                BootstrapMethodTitle(paired->difference.method));
  for (int s = 0; s < kNumCocoStats; ++s) {
    const double sa = a.stats[s], sb = b.stats[s];
    out += fmt::format("{:<6} A {:6.3f}  B {:6.3f}", CocoStatNames()[s], sa, sb);
    if (sa < 0 || sb < 0) {
      out += "  A - B undefined (no ground truth)\n";
      continue;
    }
    out += fmt::format("  A - B {:+.3f}", sa - sb);
    if (paired != nullptr) {
      const BootstrapInterval& d = paired->difference.stats[s];
      out += fmt::format(" [{:+.3f}, {:+.3f}]", d.lower, d.upper);
    }
    out += "\n";
  }
  return out;
}

CocoEvaluationResult RunCocoEvaluation(const CocoEvaluationOptions& options) {
  options.Check();
  std::optional<StagedFolder> out;
  if (!options.out.empty()) {
    CheckOutputDoesNotOverlapInputs(
        "--out", options.out,
        {{"--coco-gt", options.gt},
         {"--coco-det", options.det},
         {"--coco-det-b", options.det_b.empty() ? options.det : options.det_b}});
    out.emplace(options.out, "eval", std::vector<std::string>{kMakerEval});
  }
  CocoEvaluationResult run;
  const Timer read_timer;
  const std::string gt_text = ReadFile(options.gt, kMaxReadFileBytes, "COCO ground truth");
  const CocoGroundTruth gt = ParseCocoGroundTruth(gt_text, options.gt.string());
  // The inputs' hash only for results.json (hashing the results file cost a twentieth of a run).
  uint64_t hash = out ? Fnv1a64(gt_text) : 0;
  uint64_t* const hashing = out ? &hash : nullptr;
  const std::vector<CocoDetection> dets = ReadCocoDetections(options.det, gt, hashing);
  std::vector<CocoDetection> dets_b;
  if (!options.det_b.empty()) dets_b = ReadCocoDetections(options.det_b, gt, hashing);
  if (out) run.input_hash = HashHex(hash);
  run.read_seconds = read_timer.ElapsedSeconds();
  // Each evaluation once: the bootstraps hand over the evaluations they resample.
  if (options.bootstrap && !options.det_b.empty()) {
    run.result_b.emplace();
    run.paired = PairedBootstrapCoco(gt, dets, dets_b, options.eval, *options.bootstrap,
                                     &run.result, &*run.result_b);
    run.bootstrap = run.paired->a;
  } else if (options.bootstrap) {
    run.bootstrap = BootstrapCoco(gt, dets, options.eval, *options.bootstrap, &run.result);
  } else {
    run.result = EvaluateCoco(gt, dets, options.eval);
    if (!options.det_b.empty()) run.result_b = EvaluateCoco(gt, dets_b, options.eval);
  }
  if (!out) return run;

  const CocoEvalResult& r = run.result;
  const CocoEvalOptions& o = r.options;
  const size_t T = o.iou_thresholds.size(), R = o.recall_thresholds.size(),
               K = r.category_ids.size(), A = o.area_ranges.size(), M = o.max_dets.size();
  const fs::path& staging = out->path();
  WriteFileAtomically(staging / "precision.npy", NpyFloat64({T, R, K, A, M}, r.precision));
  WriteFileAtomically(staging / "recall.npy", NpyFloat64({T, K, A, M}, r.recall));
  WriteFileAtomically(staging / "scores.npy", NpyFloat64({T, R, K, A, M}, r.scores));
  std::vector<std::string> names = {"precision.npy", "recall.npy", "scores.npy"};
  if (o.score_metrics) {
    WriteFileAtomically(staging / "cells.csv", CellsCsv(r));
    WriteFileAtomically(staging / "reliability.csv", ReliabilityCsv(r));
    names.insert(names.end(), {"cells.csv", "reliability.csv"});
  }
  // results.json last: the folder's marker.
  WriteFileAtomically(staging / "results.json", ResultsJson(options, run).dump(2) + "\n");
  names.push_back("results.json");
  for (const std::string& name : names) run.files.push_back(options.out / name);
  out->Commit();
  return run;
}

}  // namespace stereodet
