#include "stereodet/eval/bootstrap.h"

#include <algorithm>
#include <array>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <functional>
#include <numeric>
#include <utility>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/curve_events_internal.h"
#include "stereodet/eval/curves.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/openpcdet_compat_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/score_metrics_internal.h"
#include "stereodet/eval/voc_matcher_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Values = std::array<double, kNumBootstrapMetrics>;

Values AllNaN() {
  Values v;
  v.fill(kNaN);
  return v;
}

uint64_t SplitMix64(uint64_t* state) {
  uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A change of one frame's counts when the threshold drops to `score`: the KITTI matcher's pass 2
// counts, or an exact matcher's curve event (without the similarity: AOS is not resampled).
struct Step {
  double score = 0.0;
  int32_t frame = 0;
  int32_t tp = 0, fp = 0, fn = 0;
};

// The frames' Brier terms in Evaluate's order (ScoreMetricsAccumulator::Add), flattened, for the
// frames that have any (ascending): frame[k]'s terms are values[begin[k], begin[k + 1]). Sparse, so
// that a breakdown bin, whose terms sit in a few frames, costs a resample only those.
struct Terms {
  std::vector<int32_t> frame;
  std::vector<int32_t> begin = {0};
  std::vector<double> values;
  void Add(int32_t f, const std::vector<double>& terms) {
    if (terms.empty()) return;
    frame.push_back(f);
    values.insert(values.end(), terms.begin(), terms.end());
    begin.push_back(static_cast<int32_t>(values.size()));
  }
};

// Per-frame counts of the frames where they are not 0, ascending frame: (frame, count).
using FrameCounts = std::vector<std::pair<int32_t, int32_t>>;

int64_t WeightedSum(const FrameCounts& counts, const std::vector<int32_t>& w) {
  int64_t sum = 0;
  for (const auto& [f, count] : counts) sum += static_cast<int64_t>(w[f]) * count;
  return sum;
}

// What the resamples of one breakdown bin of a cell need, per frame (BreakdownBin's figures).
struct BinData {
  FrameCounts valid_labels;  // the cell's valid labels in the bin (CountValidLabels)
  FrameCounts base_fn;       // exact matchers: the bin's FN with no detection (the curve's start)
  // KITTI: the bin's tally of pass 2's association (TP, FP), changing only at the frame's own
  // scores; exact matchers: the bin's curve events (AssociationEvents). Descending score.
  std::vector<Step> steps;
  Terms label_terms, det_terms, all_terms;
};

// What the resamples of one class x overlap kind x difficulty need, per frame.
struct CellData {
  size_t class_kind = 0;              // index into Prepared::evaluable
  std::vector<int32_t> valid_labels;  // per frame (the devkit's n_gt share)
  std::vector<double> tp_scores;      // KITTI pass 1, descending
  std::vector<int32_t> tp_frames;     // the frame of each
  std::vector<Step> steps;            // descending score, then frame
  Terms label_terms, det_terms, all_terms;
  std::vector<BinData> bins;  // EvalOptions::breakdowns' bins (none for a cell not evaluated)
  size_t first_bin = 0;       // the index of bins[0]'s values after every cell's (CellValues)
};

struct Prepared {
  Matcher matcher = Matcher::kKitti;
  EvalCompat compat = EvalCompat::kDevkit;
  bool always_evaluated = false;                // openpcdet compat or !require_detections
  bool needs_probabilities = true;              // score_transform kNone: scores must be in [0, 1]
  std::vector<uint8_t> outside_unit;            // per frame: a score < 0 or > 1 (any class)
  std::vector<std::vector<uint8_t>> evaluable;  // per class x kind, per frame
  std::vector<BootstrapCell> headers;           // the cells, intervals empty
  std::vector<CellData> cells;
  size_t num_bins = 0;  // over all cells
};

// The Brier terms of one frame at the operating point's association `a`, in the order
// ScoreMetricsAccumulator::Add sums them, with `selection` (a breakdown bin) or without (nullptr).
struct FrameTerms {
  std::vector<double> label_terms, det_terms, all_terms;
};
FrameTerms BrierTerms(const ClassFrame& cf, const FrameAssociation& a, Difficulty difficulty,
                      ScoreTransform transform, const MaskView* selection) {
  FrameTerms out;
  auto on_label = [&](double term, int, int) {
    out.label_terms.push_back(term);
    out.all_terms.push_back(term);
  };
  auto on_detection = [&](double s, Outcome o, int) {
    const double y = o == Outcome::kTp ? 1.0 : 0.0;
    out.det_terms.push_back((s - y) * (s - y));
    if (o == Outcome::kFp) out.all_terms.push_back(s * s);
  };
  if (selection == nullptr) {
    ForEachBrierTerm(cf, a, difficulty, transform, KeepEverything{}, on_label, on_detection);
  } else {
    ForEachBrierTerm(cf, a, difficulty, transform, *selection, on_label, on_detection);
  }
  return out;
}

// Frame f's statistics for one breakdown bin (see BinData).
struct FrameBin {
  int32_t valid_labels = 0, base_fn = 0;
  std::vector<Step> steps;
  FrameTerms terms;
};

// Frame f's per-frame statistics for one cell (see CellData), from its ClassFrame.
struct FrameCell {
  int32_t valid_labels = 0;
  std::vector<double> tp_scores;
  std::vector<Step> steps;
  FrameTerms terms;
  std::vector<FrameBin> bins;
};

// `frame` is the EvalFrame `cf` was prepared from; `bins`: the breakdown bins' selections.
FrameCell FrameStatistics(int32_t f, const EvalFrame& frame, const ClassFrame& cf,
                          Difficulty difficulty, const EvalOptions& eval,
                          const std::vector<StableSelection>& bins) {
  FrameCell out;
  out.bins.resize(bins.size());
  const BinMasks masks = MaskBins(frame, cf, bins);
  for (int i = 0; i < cf.num_labels(); ++i) {
    if (!cf.LabelValid(i, difficulty)) continue;
    ++out.valid_labels;
    for (size_t s = 0; s < bins.size(); ++s) out.bins[s].valid_labels += masks.Bin(s).KeepsLabel(i);
  }
  if (eval.matcher == Matcher::kKitti) {
    out.tp_scores = KittiCollectTpScores(cf, difficulty).scores;
    // Pass 2's counts change only where a detection of the frame enters: at its distinct scores.
    const std::vector<double> scores = cf.DistinctScores();
    if (!bins.empty()) {
      // The bins' tallies of pass 2's association (KittiPasses' bin counts) at each distinct
      // score; above the highest, no detection takes part: 0 TP, 0 FP.
      std::vector<Tally> previous(bins.size()), current(bins.size());
      for (const double score : scores) {
        const FrameAssociation a = KittiAssociate(cf, difficulty, score);
        std::fill(current.begin(), current.end(), Tally{});
        TallyBins(cf, a, masks, bins.size(), current.data());
        for (size_t s = 0; s < bins.size(); ++s) {
          const Tally& t = current[s];
          if (t.tp != previous[s].tp || t.fp != previous[s].fp) {
            out.bins[s].steps.push_back(Step{score, f, static_cast<int32_t>(t.tp - previous[s].tp),
                                             static_cast<int32_t>(t.fp - previous[s].fp), 0});
          }
          previous[s] = t;
        }
      }
    }
    if (!scores.empty()) {
      const std::vector<KittiCounts> counts = KittiAddFrameCounts(cf, difficulty, scores);
      KittiCounts previous;
      previous.fn = out.valid_labels;
      for (size_t k = 0; k < scores.size(); ++k) {
        const KittiCounts& c = counts[k];
        if (c.tp != previous.tp || c.fp != previous.fp || c.fn != previous.fn) {
          out.steps.push_back(Step{scores[k], f, static_cast<int32_t>(c.tp - previous.tp),
                                   static_cast<int32_t>(c.fp - previous.fp),
                                   static_cast<int32_t>(c.fn - previous.fn)});
        }
        previous = c;
      }
    }
  } else {
    // Every event is kept, zero ones too: BuildCurve makes a point at each of their scores.
    const std::vector<CurveEvent> events = eval.matcher == Matcher::kOptimal
                                               ? OptimalFrameEvents(cf, difficulty)
                                               : VocFrameEvents(cf, difficulty);
    for (const CurveEvent& e : events) out.steps.push_back(Step{e.score, f, e.tp, e.fp, e.fn});
    if (!bins.empty()) {
      // The bins' curve events (ExactCurve's). Without the similarity, which only adds
      // points that repeat their predecessor's precision and recall: no AP changes.
      const std::vector<FrameCurveEvents> bin_events =
          AssociationEvents(eval.matcher, cf, difficulty, masks, bins.size(), /*with_aos=*/false);
      for (size_t s = 0; s < bins.size(); ++s) {
        out.bins[s].base_fn = static_cast<int32_t>(bin_events[s].base_fn);
        for (const CurveEvent& e : bin_events[s].events) {
          out.bins[s].steps.push_back(Step{e.score, f, e.tp, e.fp, e.fn});
        }
      }
    }
  }
  // The Brier terms at the operating point, as ScoreMetricsAccumulator::Add sums them: the cell's
  // and each bin's, from one association.
  const FrameAssociation a = Associate(eval.matcher, cf, difficulty, eval.score_threshold);
  out.terms = BrierTerms(cf, a, difficulty, eval.score_transform, nullptr);
  for (size_t s = 0; s < bins.size(); ++s) {
    const MaskView mask = masks.Bin(s);
    out.bins[s].terms = BrierTerms(cf, a, difficulty, eval.score_transform, &mask);
  }
  return out;
}

void AddTerms(int32_t f, const FrameTerms& frame_terms, Terms* labels, Terms* detections,
              Terms* all) {
  labels->Add(f, frame_terms.label_terms);
  detections->Add(f, frame_terms.det_terms);
  all->Add(f, frame_terms.all_terms);
}

void SortByDescendingScore(std::vector<Step>* steps) {
  std::stable_sort(steps->begin(), steps->end(),
                   [](const Step& a, const Step& b) { return a.score > b.score; });
}

// Per-frame statistics of every cell, in Evaluate's cell order, and without `with_breakdowns`
// none of eval.breakdowns' bins.
Prepared Prepare(const std::vector<EvalFrame>& frames, const EvalOptions& eval,
                 bool with_breakdowns) {
  Prepared p;
  p.matcher = eval.matcher;
  p.compat = eval.compat;
  p.always_evaluated = eval.compat == EvalCompat::kOpenPcdet || !eval.require_detections;
  p.needs_probabilities = eval.score_transform == ScoreTransform::kNone;
  const size_t n = frames.size();
  const int threads = eval.num_threads;
  p.outside_unit.assign(n, 0);
  for (size_t f = 0; f < n; ++f) {
    for (const Object& d : frames[f].detections) {
      const double score = d.score.value_or(0.0);
      if (score < 0 || score > 1) p.outside_unit[f] = 1;
    }
  }
  const OverlapArithmetic arithmetic =
      eval.matcher == Matcher::kKitti ? OverlapArithmetic::kDevkit : OverlapArithmetic::kExact;
  // The bins of every breakdown, in Evaluate's order (ClassResult::breakdown).
  std::vector<StableSelection> bins;
  std::vector<BootstrapBin> bin_headers;
  if (with_breakdowns) {
    for (const BreakdownOptions& breakdown : eval.breakdowns) {
      for (int b = 0; b < breakdown.num_bins(); ++b) {
        bins.push_back(
            StableSelection::Bin(breakdown.axis, breakdown.edges[b], breakdown.edges[b + 1]));
        BootstrapBin header;
        header.axis = breakdown.axis;
        header.lower = breakdown.edges[b];
        header.upper = breakdown.edges[b + 1];
        bin_headers.push_back(header);
      }
    }
  }
  std::vector<ClassFrame> cfs(n);
  for (const ClassSpec& spec : eval.classes) {
    for (const OverlapKind kind : eval.metrics) {
      // Whether each frame alone has a detection the devkit would evaluate the class for.
      std::vector<uint8_t> evaluable(n, 0);
      if (!p.always_evaluated) {
        ParallelFor(
            n,
            [&](size_t f) {
              EvalFrame detections_only;
              for (const Object& d : frames[f].detections) {
                if (EqualsIgnoreCase(d.type, spec.name)) detections_only.detections.push_back(d);
              }
              evaluable[f] = HasEvaluableDetection({detections_only}, spec, kind) ? 1 : 0;
            },
            threads);
      }
      const bool evaluated =
          p.always_evaluated || std::find(evaluable.begin(), evaluable.end(), 1) != evaluable.end();
      const size_t class_kind = p.evaluable.size();
      p.evaluable.push_back(std::move(evaluable));
      if (evaluated) {
        ParallelFor(
            n,
            [&](size_t f) {
              cfs[f] = eval.compat == EvalCompat::kOpenPcdet
                           ? PrepareClassFrameOpenPcdet(frames[f], spec, kind, std::move(cfs[f]))
                           : PrepareClassFrame(frames[f], spec, kind, arithmetic, std::move(cfs[f]),
                                               /*reuse_selection=*/false, eval.let);
            },
            threads);
      }
      for (const Difficulty difficulty : eval.difficulties) {
        BootstrapCell header;
        header.class_name = spec.name;
        header.metric = kind;
        header.difficulty = difficulty;
        header.evaluated = evaluated;
        if (evaluated) header.breakdown = bin_headers;
        p.headers.push_back(header);
        CellData cell;
        cell.class_kind = class_kind;
        if (evaluated) {
          std::vector<FrameCell> per_frame(n);
          ParallelFor(
              n,
              [&](size_t f) {
                per_frame[f] = FrameStatistics(static_cast<int32_t>(f), frames[f], cfs[f],
                                               difficulty, eval, bins);
              },
              threads);
          cell.valid_labels.resize(n);
          cell.bins.resize(bins.size());
          cell.first_bin = p.num_bins;
          p.num_bins += bins.size();
          std::vector<std::pair<double, int32_t>> tp;
          for (size_t f = 0; f < n; ++f) {
            FrameCell& fc = per_frame[f];
            const auto f32 = static_cast<int32_t>(f);
            cell.valid_labels[f] = fc.valid_labels;
            for (const double s : fc.tp_scores) tp.emplace_back(s, f32);
            cell.steps.insert(cell.steps.end(), fc.steps.begin(), fc.steps.end());
            AddTerms(f32, fc.terms, &cell.label_terms, &cell.det_terms, &cell.all_terms);
            for (size_t s = 0; s < bins.size(); ++s) {
              const FrameBin& fb = fc.bins[s];
              BinData& bin = cell.bins[s];
              if (fb.valid_labels != 0) bin.valid_labels.emplace_back(f32, fb.valid_labels);
              if (fb.base_fn != 0) bin.base_fn.emplace_back(f32, fb.base_fn);
              bin.steps.insert(bin.steps.end(), fb.steps.begin(), fb.steps.end());
              AddTerms(f32, fb.terms, &bin.label_terms, &bin.det_terms, &bin.all_terms);
            }
            fc = FrameCell();  // its memory back, as the frames are gathered
          }
          std::stable_sort(tp.begin(), tp.end(),
                           [](const auto& a, const auto& b) { return a.first > b.first; });
          for (const auto& [score, f] : tp) {
            cell.tp_scores.push_back(score);
            cell.tp_frames.push_back(f);
          }
          SortByDescendingScore(&cell.steps);
          for (BinData& bin : cell.bins) SortByDescendingScore(&bin.steps);
        }
        p.cells.push_back(std::move(cell));
      }
    }
  }
  return p;
}

// The mean of the terms of the resample's frames, each frame's terms once per draw, summed in the
// order Evaluate sums them on the frame list with frame f repeated w[f] times.
double WeightedMean(const Terms& terms, const std::vector<int32_t>& w) {
  double sum = 0.0;
  int64_t count = 0;
  for (size_t k = 0; k < terms.frame.size(); ++k) {
    const int32_t m = w[terms.frame[k]];
    if (m == 0) continue;
    const int32_t b = terms.begin[k], e = terms.begin[k + 1];
    for (int32_t r = 0; r < m; ++r) {
      for (int32_t t = b; t < e; ++t) sum += terms.values[t];
    }
    count += static_cast<int64_t>(m) * (e - b);
  }
  return count > 0 ? sum / static_cast<double>(count) : kNaN;
}

// The devkit's thresholds of the resample for a cell (getThresholds on its TP scores, each frame's
// repeated w[f] times, and its n_gt), at most kKittiSamplePoints of them.
std::vector<double> KittiResampleThresholds(const CellData& cell, const std::vector<int32_t>& w) {
  int64_t n_gt = 0;
  for (size_t f = 0; f < w.size(); ++f) n_gt += static_cast<int64_t>(w[f]) * cell.valid_labels[f];
  std::vector<double> scores;
  scores.reserve(cell.tp_scores.size());
  for (size_t k = 0; k < cell.tp_scores.size(); ++k) {
    scores.insert(scores.end(), w[cell.tp_frames[k]], cell.tp_scores[k]);
  }
  std::vector<double> thresholds = KittiThresholds(std::move(scores), static_cast<double>(n_gt));
  if (thresholds.size() > kKittiSamplePoints) thresholds.resize(kKittiSamplePoints);
  return thresholds;
}

// AP_R40 and AP_R11 of the KITTI matcher on the resample from `steps` counted at `thresholds`: the
// cell's (KittiPasses' arithmetic: 0 / 0 kept as NaN, the devkit's or with `openpcdet_envelope`
// numpy's envelope), or with `empty_slots_zero` a breakdown bin's (KittiSelectionCurve's: precision
// 0 where the bin holds no detection, the devkit's envelope).
void KittiAp(const std::vector<Step>& steps, const std::vector<double>& thresholds,
             const std::vector<int32_t>& w, bool openpcdet_envelope, bool empty_slots_zero,
             Values* v) {
  std::array<double, kKittiSamplePoints> precision{};
  int64_t tp = 0, fp = 0;
  size_t k = 0;
  for (size_t t = 0; t < thresholds.size(); ++t) {
    for (; k < steps.size() && steps[k].score >= thresholds[t]; ++k) {
      const Step& s = steps[k];
      tp += static_cast<int64_t>(w[s.frame]) * s.tp;
      fp += static_cast<int64_t>(w[s.frame]) * s.fp;
    }
    precision[t] = empty_slots_zero && tp + fp == 0
                       ? 0.0
                       : static_cast<double>(tp) / static_cast<double>(tp + fp);
  }
  if (openpcdet_envelope) {
    precision = OpenPcdetEnvelope(precision);
  } else {
    for (size_t t = 0; t < thresholds.size(); ++t) {
      precision[t] = *std::max_element(precision.begin() + t, precision.end());
    }
  }
  (*v)[static_cast<int>(BootstrapMetric::kApR40)] = KittiApR40(precision);
  (*v)[static_cast<int>(BootstrapMetric::kApR11)] = KittiApR11(precision);
}

// AP_R40, AP_R11 and every-point AP of the exact curve (BuildCurve on the resample's events),
// starting from `base_fn` FN.
void ExactAp(const std::vector<Step>& steps, int64_t base_fn, const std::vector<int32_t>& w,
             Values* v) {
  CurvePoint current;
  current.fn = base_fn;
  std::vector<CurvePoint> curve;
  for (size_t i = 0; i < steps.size();) {
    const double score = steps[i].score;
    bool present = false;
    for (; i < steps.size() && steps[i].score == score; ++i) {
      const Step& s = steps[i];
      const int64_t m = w[s.frame];
      if (m == 0) continue;
      present = true;
      current.tp += m * s.tp;
      current.fp += m * s.fp;
      current.fn += m * s.fn;
    }
    if (!present) continue;
    current.threshold = score;
    current = FinishPoint(current);
    curve.push_back(current);
  }
  (*v)[static_cast<int>(BootstrapMetric::kApR40)] = InterpolatedApR40(curve);
  (*v)[static_cast<int>(BootstrapMetric::kApR11)] = InterpolatedApR11(curve);
  (*v)[static_cast<int>(BootstrapMetric::kApVoc)] = EveryPointAp(curve);
}

void WeightedBrier(const Terms& labels, const Terms& detections, const Terms& all,
                   const std::vector<int32_t>& w, Values* v) {
  (*v)[static_cast<int>(BootstrapMetric::kBrierLabels)] = WeightedMean(labels, w);
  (*v)[static_cast<int>(BootstrapMetric::kBrierDetections)] = WeightedMean(detections, w);
  (*v)[static_cast<int>(BootstrapMetric::kBrierAll)] = WeightedMean(all, w);
}

// Every cell's metrics on the resample with frame counts `w`, then every bin's: cell c's bin k at
// p.cells.size() + p.cells[c].first_bin + k.
std::vector<Values> CellValues(const Prepared& p, const std::vector<int32_t>& w) {
  const size_t n = w.size();
  std::vector<uint8_t> evaluated(p.evaluable.size(), 1);
  if (!p.always_evaluated) {
    for (size_t c = 0; c < p.evaluable.size(); ++c) {
      evaluated[c] = 0;
      for (size_t f = 0; f < n && !evaluated[c]; ++f) evaluated[c] = w[f] > 0 && p.evaluable[c][f];
    }
  }
  bool probabilities = true;
  if (p.needs_probabilities) {
    for (size_t f = 0; f < n && probabilities; ++f)
      probabilities = !(w[f] > 0 && p.outside_unit[f]);
  }
  const bool kitti = p.matcher == Matcher::kKitti;
  std::vector<Values> out(p.cells.size() + p.num_bins, AllNaN());
  for (size_t c = 0; c < p.cells.size(); ++c) {
    const CellData& cell = p.cells[c];
    if (!p.headers[c].evaluated || !evaluated[cell.class_kind]) continue;
    Values& v = out[c];
    // KITTI: the cell's thresholds serve its bins too (Evaluate's ClassResult::kitti_thresholds).
    std::vector<double> thresholds;
    if (kitti) {
      thresholds = KittiResampleThresholds(cell, w);
      KittiAp(cell.steps, thresholds, w, p.compat == EvalCompat::kOpenPcdet,
              /*empty_slots_zero=*/false, &v);
    } else {
      int64_t base_fn = 0;
      for (size_t f = 0; f < n; ++f) base_fn += static_cast<int64_t>(w[f]) * cell.valid_labels[f];
      ExactAp(cell.steps, base_fn, w, &v);
    }
    if (probabilities) WeightedBrier(cell.label_terms, cell.det_terms, cell.all_terms, w, &v);
    for (size_t k = 0; k < cell.bins.size(); ++k) {
      const BinData& bin = cell.bins[k];
      Values& bv = out[p.cells.size() + cell.first_bin + k];
      if (WeightedSum(bin.valid_labels, w) > 0) {  // else no recall: AP undefined, as Evaluate's
        if (kitti) {
          KittiAp(bin.steps, thresholds, w, /*openpcdet_envelope=*/false,
                  /*empty_slots_zero=*/true, &bv);
        } else {
          ExactAp(bin.steps, WeightedSum(bin.base_fn, w), w, &bv);
        }
      }
      if (probabilities) WeightedBrier(bin.label_terms, bin.det_terms, bin.all_terms, w, &bv);
    }
  }
  return out;
}

// The result of the estimates and the resamples' values (per_resample[r][cell][metric]).
// With BootstrapMethod::kBca, `jackknife[g][cell][metric]` holds the leave-group-out values.
BootstrapResult MakeResult(const Prepared& p, const BootstrapOptions& options,
                           const std::vector<Values>& estimate,
                           const std::vector<std::vector<Values>>& per_resample,
                           const std::vector<std::vector<Values>>& jackknife) {
  BootstrapResult result;
  result.num_resamples = options.num_resamples;
  result.seed = options.seed;
  result.confidence = options.confidence;
  result.matcher = p.matcher;
  result.method = options.method;
  result.cells = p.headers;
  std::vector<double> samples(per_resample.size()), jack(jackknife.size());
  // The intervals of the values at `index` (CellValues' order).
  auto fill = [&](size_t index, std::array<BootstrapInterval, kNumBootstrapMetrics>* intervals) {
    for (int m = 0; m < kNumBootstrapMetrics; ++m) {
      BootstrapInterval& interval = (*intervals)[m];
      interval.estimate = estimate[index][m];
      for (size_t r = 0; r < per_resample.size(); ++r) samples[r] = per_resample[r][index][m];
      for (size_t g = 0; g < jackknife.size(); ++g) jack[g] = jackknife[g][index][m];
      FillInterval(options, samples, jack, &interval);
    }
  };
  for (size_t c = 0; c < result.cells.size(); ++c) {
    BootstrapCell& cell = result.cells[c];
    fill(c, &cell.intervals);
    for (size_t k = 0; k < cell.breakdown.size(); ++k) {
      fill(p.cells.size() + p.cells[c].first_bin + k, &cell.breakdown[k].intervals);
    }
  }
  return result;
}

// A - B of CellValues' values of two preparations of the same frames and options, in A's order:
// each cell, then each bin of A's cells. A cell's bins exist only where the cell is evaluated, so
// the two orders of bins differ where a cell is evaluated in one set alone: its bins' differences
// are NaN (as the cell's are, one side being NaN).
std::vector<Values> Difference(const Prepared& pa, const Prepared& pb, const std::vector<Values>& a,
                               const std::vector<Values>& b) {
  std::vector<Values> d(a.size(), AllNaN());
  auto subtract = [&](size_t ia, size_t ib) {
    for (int m = 0; m < kNumBootstrapMetrics; ++m) d[ia][m] = a[ia][m] - b[ib][m];  // NaN stays
  };
  const size_t num_cells = pa.cells.size();
  for (size_t c = 0; c < num_cells; ++c) {
    subtract(c, c);
    const CellData& ca = pa.cells[c];
    const CellData& cb = pb.cells[c];
    if (ca.bins.size() != cb.bins.size()) continue;
    for (size_t k = 0; k < ca.bins.size(); ++k) {
      subtract(num_cells + ca.first_bin + k, num_cells + cb.first_bin + k);
    }
  }
  return d;
}

}  // namespace

void BootstrapOptions::Check() const {
  STEREODET_CHECK(num_resamples >= 1 && num_resamples <= kMaxBootstrapResamples)
      << "bootstrap: resamples must be in [1, " << kMaxBootstrapResamples << "], got "
      << num_resamples;
  STEREODET_CHECK(confidence > 0 && confidence < 1)
      << "bootstrap: confidence must be in (0, 1), got " << confidence;
  STEREODET_CHECK(jackknife_groups >= 2)
      << "bootstrap: jackknife_groups must be at least 2, got " << jackknife_groups;
}

const char* BootstrapMetricName(BootstrapMetric metric) {
  switch (metric) {
    case BootstrapMetric::kApR40:
      return "ap_r40";
    case BootstrapMetric::kApR11:
      return "ap_r11";
    case BootstrapMetric::kApVoc:
      return "ap_voc";
    case BootstrapMetric::kBrierLabels:
      return "brier_labels";
    case BootstrapMetric::kBrierDetections:
      return "brier_detections";
    case BootstrapMetric::kBrierAll:
      return "brier_all";
  }
  return "?";
}

std::optional<BootstrapMetric> ParseBootstrapMetric(std::string_view text) {
  for (int m = 0; m < kNumBootstrapMetrics; ++m) {
    const auto metric = static_cast<BootstrapMetric>(m);
    if (text == BootstrapMetricName(metric)) return metric;
  }
  return std::nullopt;
}

std::vector<BootstrapMetric> BootstrapMetrics(Matcher matcher) {
  std::vector<BootstrapMetric> out;
  for (int m = 0; m < kNumBootstrapMetrics; ++m) {
    const auto metric = static_cast<BootstrapMetric>(m);
    if (metric == BootstrapMetric::kApVoc && matcher == Matcher::kKitti) continue;
    out.push_back(metric);
  }
  return out;
}

const BootstrapCell* BootstrapResult::Find(const std::string& class_name, OverlapKind metric,
                                           Difficulty difficulty) const {
  for (const BootstrapCell& c : cells) {
    if (EqualsIgnoreCase(c.class_name, class_name) && c.metric == metric &&
        c.difficulty == difficulty) {
      return &c;
    }
  }
  return nullptr;
}

namespace {

// The numbers among `values` (NaN left out), in their order.
std::vector<double> Defined(const std::vector<double>& values) {
  std::vector<double> defined;
  defined.reserve(values.size());
  for (const double v : values) {
    if (!std::isnan(v)) defined.push_back(v);
  }
  return defined;
}

}  // namespace

void FillBootstrapInterval(const std::vector<double>& samples, double confidence, bool keep,
                           BootstrapInterval* interval) {
  std::vector<double> defined = Defined(samples);
  interval->num_defined = static_cast<int64_t>(defined.size());
  std::sort(defined.begin(), defined.end());
  interval->lower = Quantile(defined, (1 - confidence) / 2);
  interval->upper = Quantile(defined, (1 + confidence) / 2);
  if (keep) interval->samples = samples;
}

void FillBcaInterval(const std::vector<double>& samples, const std::vector<double>& jackknife,
                     double confidence, bool keep, BootstrapInterval* interval) {
  const std::vector<double> defined = Defined(samples);
  interval->num_defined = static_cast<int64_t>(defined.size());
  if (keep) interval->samples = samples;
  interval->lower = interval->upper = kNaN;
  interval->bias_correction = interval->acceleration = kNaN;
  const double estimate = interval->estimate;
  if (std::isnan(estimate) || defined.empty()) return;
  double below = 0;
  for (const double s : defined) below += s < estimate ? 1.0 : s == estimate ? 0.5 : 0.0;
  const double share = below / static_cast<double>(defined.size());
  if (share <= 0 || share >= 1) return;  // z0 infinite: every resample on one side
  const std::vector<double> jack = Defined(jackknife);
  if (jack.size() < 2) return;
  const boost::math::normal normal;
  const double z0 = boost::math::quantile(normal, share);
  const double mean = std::accumulate(jack.begin(), jack.end(), 0.0) / jack.size();
  double num = 0, den = 0;
  for (const double j : jack) {
    const double d = mean - j;
    num += d * d * d;
    den += d * d;
  }
  const double a = den > 0 ? num / (6 * std::pow(den, 1.5)) : 0.0;
  // The bound's quantile level; NaN where the acceleration folds the correction over.
  auto bound = [&](double z) {
    const double shifted = z0 + z;
    const double denominator = 1 - a * shifted;
    if (!(denominator > 0)) return kNaN;
    return Quantile(defined, boost::math::cdf(normal, z0 + shifted / denominator));
  };
  const double alpha = (1 - confidence) / 2;
  interval->lower = bound(boost::math::quantile(normal, alpha));
  interval->upper = bound(boost::math::quantile(normal, 1 - alpha));
  interval->bias_correction = z0;
  interval->acceleration = a;
}

void FillInterval(const BootstrapOptions& options, const std::vector<double>& samples,
                  const std::vector<double>& jackknife, BootstrapInterval* interval) {
  if (options.method == BootstrapMethod::kBca) {
    FillBcaInterval(samples, jackknife, options.confidence, options.keep_samples, interval);
  } else {
    FillBootstrapInterval(samples, options.confidence, options.keep_samples, interval);
  }
}

int JackknifeGroupCount(int64_t num_frames, int groups) {
  return static_cast<int>(std::min<int64_t>(groups, num_frames));
}

std::vector<int32_t> JackknifeFrameCounts(int64_t num_frames, int groups, int g) {
  const int count = JackknifeGroupCount(num_frames, groups);
  STEREODET_CHECK(g >= 0 && g < count) << "jackknife group " << g << " of " << count;
  std::vector<int32_t> w(num_frames, 1);
  const int64_t begin = num_frames * g / count, end = num_frames * (g + 1) / count;
  for (int64_t f = begin; f < end; ++f) w[f] = 0;
  return w;
}

const char* BootstrapMethodName(BootstrapMethod method) {
  return method == BootstrapMethod::kBca ? "bca" : "percentile";
}

const char* BootstrapMethodTitle(BootstrapMethod method) {
  return method == BootstrapMethod::kBca ? "BCa" : "percentile";
}

std::optional<BootstrapMethod> ParseBootstrapMethod(std::string_view text) {
  if (text == "percentile") return BootstrapMethod::kPercentile;
  if (text == "bca") return BootstrapMethod::kBca;
  return std::nullopt;
}

std::vector<int32_t> BootstrapFrameCounts(int64_t num_frames, uint64_t seed, int64_t resample) {
  STEREODET_CHECK(num_frames >= 0 && num_frames <= std::numeric_limits<int32_t>::max())
      << "bootstrap: bad frame count " << num_frames;
  std::vector<int32_t> counts(num_frames, 0);
  if (num_frames == 0) return counts;
  // The stream's state: the seed and the resample index, each mixed, so that neighbouring seeds
  // and resamples give unrelated streams.
  uint64_t mix = seed;
  uint64_t state = SplitMix64(&mix);
  mix = static_cast<uint64_t>(resample) ^ 0x5851F42D4C957F2Dull;
  state ^= SplitMix64(&mix);
  // Unbiased: draws at or above the largest multiple of n that fits are drawn again.
  const uint64_t n = static_cast<uint64_t>(num_frames);
  const uint64_t limit =
      std::numeric_limits<uint64_t>::max() - std::numeric_limits<uint64_t>::max() % n;
  for (int64_t i = 0; i < num_frames; ++i) {
    uint64_t x;
    do {
      x = SplitMix64(&state);
    } while (x >= limit);
    ++counts[static_cast<size_t>(x % n)];
  }
  return counts;
}

namespace {

// BCa's leave-one-group-out values (JackknifeFrameCounts), [group][cell][metric]; empty for the
// percentile method.
std::vector<std::vector<Values>> Jackknife(const Prepared& p, int64_t n,
                                           const BootstrapOptions& bootstrap) {
  if (bootstrap.method != BootstrapMethod::kBca) return {};
  std::vector<std::vector<Values>> out(JackknifeGroupCount(n, bootstrap.jackknife_groups));
  ParallelFor(
      out.size(),
      [&](size_t g) {
        out[g] =
            CellValues(p, JackknifeFrameCounts(n, bootstrap.jackknife_groups, static_cast<int>(g)));
      },
      bootstrap.num_threads);
  return out;
}

}  // namespace

BootstrapResult Bootstrap(const std::vector<EvalFrame>& frames, const EvalOptions& eval,
                          const BootstrapOptions& bootstrap) {
  eval.Check();
  bootstrap.Check();
  const Timer timer;
  const Prepared p = Prepare(frames, eval, /*with_breakdowns=*/true);
  const int64_t n = static_cast<int64_t>(frames.size());
  const std::vector<Values> estimate = CellValues(p, std::vector<int32_t>(n, 1));
  std::vector<std::vector<Values>> per_resample(bootstrap.num_resamples);
  ParallelFor(
      per_resample.size(),
      [&](size_t r) {
        per_resample[r] =
            CellValues(p, BootstrapFrameCounts(n, bootstrap.seed, static_cast<int64_t>(r)));
      },
      bootstrap.num_threads);
  const std::vector<std::vector<Values>> jackknife = Jackknife(p, n, bootstrap);
  BootstrapResult result = MakeResult(p, bootstrap, estimate, per_resample, jackknife);
  result.num_frames = n;
  result.seconds = timer.ElapsedSeconds();
  return result;
}

PairedBootstrapResult PairedBootstrap(const std::vector<EvalFrame>& a,
                                      const std::vector<EvalFrame>& b, const EvalOptions& eval,
                                      const BootstrapOptions& bootstrap) {
  eval.Check();
  bootstrap.Check();
  STEREODET_CHECK(a.size() == b.size())
      << "paired bootstrap: A has " << a.size() << " frames, B " << b.size();
  for (size_t f = 0; f < a.size(); ++f) {
    STEREODET_CHECK(a[f].id == b[f].id) << "paired bootstrap: frame " << f << " is '" << a[f].id
                                        << "' in A but '" << b[f].id << "' in B";
  }
  const Timer timer;
  const Prepared pa = Prepare(a, eval, /*with_breakdowns=*/true);
  const Prepared pb = Prepare(b, eval, /*with_breakdowns=*/true);
  const int64_t n = static_cast<int64_t>(a.size());
  const std::vector<int32_t> ones(n, 1);
  const std::vector<Values> estimate_a = CellValues(pa, ones), estimate_b = CellValues(pb, ones);
  const size_t num = bootstrap.num_resamples;
  std::vector<std::vector<Values>> values_a(num), values_b(num), values_d(num);
  ParallelFor(
      num,
      [&](size_t r) {
        const std::vector<int32_t> w =
            BootstrapFrameCounts(n, bootstrap.seed, static_cast<int64_t>(r));
        values_a[r] = CellValues(pa, w);
        values_b[r] = CellValues(pb, w);
        values_d[r] = Difference(pa, pb, values_a[r], values_b[r]);
      },
      bootstrap.num_threads);
  const std::vector<std::vector<Values>> jack_a = Jackknife(pa, n, bootstrap),
                                         jack_b = Jackknife(pb, n, bootstrap);
  std::vector<std::vector<Values>> jack_d(jack_a.size());
  for (size_t g = 0; g < jack_a.size(); ++g) {
    jack_d[g] = Difference(pa, pb, jack_a[g], jack_b[g]);
  }
  PairedBootstrapResult result;
  result.a = MakeResult(pa, bootstrap, estimate_a, values_a, jack_a);
  result.b = MakeResult(pb, bootstrap, estimate_b, values_b, jack_b);
  result.difference =
      MakeResult(pa, bootstrap, Difference(pa, pb, estimate_a, estimate_b), values_d, jack_d);
  for (size_t c = 0; c < result.difference.cells.size(); ++c) {
    result.difference.cells[c].evaluated = pa.headers[c].evaluated && pb.headers[c].evaluated;
  }
  const double seconds = timer.ElapsedSeconds();
  for (BootstrapResult* r : {&result.a, &result.b, &result.difference}) {
    r->num_frames = n;
    r->seconds = seconds;
  }
  return result;
}

}  // namespace stereodet
