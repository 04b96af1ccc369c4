#include "stereodet/eval/evaluator.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stereodet/eval/optimal_matcher.h"
#include "stereodet/eval/voc_matcher.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<ClassFrame> PrepareAll(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                                   OverlapKind kind, int num_threads) {
  std::vector<ClassFrame> out(frames.size());
  ParallelFor(frames.size(), [&](size_t i) { out[i] = PrepareClassFrame(frames[i], spec, kind); },
              num_threads);
  return out;
}

// The frames with the labels and detections that fail `conditions` struck (DontCare regions stay).
std::vector<EvalFrame> StrikeFailing(const std::vector<EvalFrame>& frames,
                                     const std::vector<FilterCondition>& conditions, int num_threads) {
  std::vector<EvalFrame> out(frames.size());
  ParallelFor(frames.size(), [&](size_t i) {
    out[i].id = frames[i].id;
    for (const Object& label : frames[i].labels) {
      if (EqualsIgnoreCase(label.type, "DontCare") || PassesFilter(label, true, conditions)) {
        out[i].labels.push_back(label);
      }
    }
    for (const Object& det : frames[i].detections) {
      if (PassesFilter(det, false, conditions)) out[i].detections.push_back(det);
    }
  }, num_threads);
  return out;
}

std::vector<FrameAssociation> AssociateAll(Matcher matcher, const std::vector<ClassFrame>& cfs,
                                           Difficulty difficulty, double threshold, int num_threads) {
  std::vector<FrameAssociation> out(cfs.size());
  ParallelFor(cfs.size(), [&](size_t i) { out[i] = Associate(matcher, cfs[i], difficulty, threshold); },
              num_threads);
  return out;
}

OperatingPoint CountAll(const std::vector<FrameAssociation>& assocs, double threshold) {
  int64_t tp = 0, fp = 0, fn = 0;
  for (const FrameAssociation& a : assocs) {
    tp += a.CountDets(Outcome::kTp);
    fp += a.CountDets(Outcome::kFp);
    fn += a.CountLabels(Outcome::kFn);
  }
  return MakeOperatingPoint(threshold, tp, fp, fn);
}

// Stable filter: the unfiltered association, keeping pairs whose both sides pass and unmatched
// labels / detections that pass.
OperatingPoint CountStable(const std::vector<EvalFrame>& frames, const std::vector<ClassFrame>& cfs,
                           const std::vector<FrameAssociation>& assocs,
                           const std::vector<FilterCondition>& conditions, double threshold) {
  int64_t tp = 0, fp = 0, fn = 0;
  for (size_t f = 0; f < frames.size(); ++f) {
    const ClassFrame& cf = cfs[f];
    const FrameAssociation& a = assocs[f];
    auto label_passes = [&](int i) {
      return PassesFilter(frames[f].labels[cf.label_object[i]], true, conditions);
    };
    auto det_passes = [&](int j) {
      return PassesFilter(frames[f].detections[cf.det_object[j]], false, conditions);
    };
    for (int i = 0; i < cf.num_labels(); ++i) {
      if (a.label_outcome[i] == Outcome::kTp) {
        if (label_passes(i) && det_passes(a.label_det[i])) ++tp;
      } else if (a.label_outcome[i] == Outcome::kFn) {
        if (label_passes(i)) ++fn;
      }
    }
    for (int j = 0; j < cf.num_dets(); ++j) {
      if (a.det_outcome[j] == Outcome::kFp && det_passes(j)) ++fp;
    }
  }
  return MakeOperatingPoint(threshold, tp, fp, fn);
}

// Curve and AP of the optimal or VOC matcher, exact at every score.
void ExactCurve(Matcher matcher, const std::vector<ClassFrame>& cfs, Difficulty difficulty,
                int num_threads, ClassResult* r) {
  constexpr size_t kBlock = 64;
  const size_t num_blocks = (cfs.size() + kBlock - 1) / kBlock;
  std::vector<std::vector<CurveEvent>> block_events(num_blocks);
  std::vector<int64_t> block_labels(num_blocks, 0);
  ParallelFor(num_blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(cfs.size(), (b + 1) * kBlock); ++i) {
      block_labels[b] += CountValidLabels(cfs[i], difficulty);
      if (matcher == Matcher::kOptimal) OptimalFrameEvents(cfs[i], difficulty, &block_events[b]);
      else VocFrameEvents(cfs[i], difficulty, &block_events[b]);
    }
  }, num_threads);
  std::vector<CurveEvent> events;
  r->num_valid_labels = 0;
  for (size_t b = 0; b < num_blocks; ++b) {
    r->num_valid_labels += block_labels[b];
    events.insert(events.end(), block_events[b].begin(), block_events[b].end());
  }
  r->curve = BuildCurve(std::move(events), r->num_valid_labels);
  r->ap_r40 = InterpolatedApR40(r->curve);
  r->ap_r11 = InterpolatedApR11(r->curve);
  r->ap_voc = EveryPointAp(r->curve);
  r->aos_r40 = r->aos_r11 = kNaN;
  r->has_aos = false;
}

void KittiCurve(const std::vector<ClassFrame>& cfs, Difficulty difficulty, bool with_aos,
                int num_threads, ClassResult* r) {
  const KittiClassResult k = EvaluateKittiClass(cfs, difficulty, num_threads);
  r->num_valid_labels = k.num_groundtruth;
  r->ap_r40 = k.ap_r40;
  r->ap_r11 = k.ap_r11;
  r->ap_voc = kNaN;
  r->has_aos = with_aos;
  r->aos_r40 = with_aos ? k.aos_r40 : kNaN;
  r->aos_r11 = with_aos ? k.aos_r11 : kNaN;
  r->kitti_precision.assign(k.precision.begin(), k.precision.end());
  if (with_aos) r->kitti_aos.assign(k.aos.begin(), k.aos.end());
  r->kitti_thresholds = k.thresholds;
  for (size_t t = 0; t < k.thresholds.size(); ++t) {
    CurvePoint p;
    p.threshold = k.thresholds[t];
    p.tp = k.counts[t].tp;
    p.fp = k.counts[t].fp;
    p.fn = k.counts[t].fn;
    FinishPoint(&p);
    r->curve.push_back(p);
  }
}

}  // namespace

const ClassResult* EvalResult::Find(const std::string& class_name, OverlapKind metric,
                                    Difficulty difficulty) const {
  for (const ClassResult& r : results) {
    if (EqualsIgnoreCase(r.class_name, class_name) && r.metric == metric && r.difficulty == difficulty) {
      return &r;
    }
  }
  return nullptr;
}

FrameAssociation Associate(Matcher matcher, const ClassFrame& frame, Difficulty difficulty,
                           double threshold) {
  switch (matcher) {
    case Matcher::kKitti: return KittiAssociate(frame, difficulty, threshold);
    case Matcher::kOptimal: return OptimalAssociate(frame, difficulty, threshold);
    case Matcher::kVoc: return VocAssociate(frame, difficulty, threshold);
  }
  return {};
}

EvalResult Evaluate(const std::vector<EvalFrame>& frames, const EvalOptions& options) {
  options.Check();
  const Timer timer;
  EvalResult result;
  result.num_frames = static_cast<int64_t>(frames.size());
  result.aos_computed = options.compute_aos && AllAlphasValid(frames);
  const int threads = options.num_threads;
  const double t_op = options.score_threshold;

  std::vector<EvalFrame> struck;
  if (!options.filter.empty()) struck = StrikeFailing(frames, options.filter.conditions, threads);

  for (const ClassSpec& spec : options.classes) {
    int64_t num_detections = 0;
    for (const EvalFrame& f : frames) {
      for (const Object& d : f.detections) num_detections += EqualsIgnoreCase(d.type, spec.name) ? 1 : 0;
    }
    for (const OverlapKind kind : options.metrics) {
      const bool evaluated = !options.require_detections || HasEvaluableDetection(frames, spec, kind);
      std::vector<ClassFrame> cfs, struck_cfs;
      if (evaluated) {
        cfs = PrepareAll(frames, spec, kind, threads);
        if (!options.filter.empty()) struck_cfs = PrepareAll(struck, spec, kind, threads);
      }
      for (const Difficulty difficulty : options.difficulties) {
        ClassResult r;
        r.class_name = spec.name;
        r.metric = kind;
        r.difficulty = difficulty;
        r.min_overlap = spec.min_overlap[static_cast<int>(kind)];
        r.evaluated = evaluated;
        r.num_detections = num_detections;
        if (!evaluated) {
          r.ap_r40 = r.ap_r11 = r.ap_voc = r.aos_r40 = r.aos_r11 = kNaN;
          result.results.push_back(std::move(r));
          continue;
        }
        if (options.matcher == Matcher::kKitti) {
          KittiCurve(cfs, difficulty, result.aos_computed && kind == OverlapKind::k2D, threads, &r);
        } else {
          ExactCurve(options.matcher, cfs, difficulty, threads, &r);
        }
        r.best_f1 = BestF1(r.curve);

        const std::vector<FrameAssociation> assocs =
            AssociateAll(options.matcher, cfs, difficulty, t_op, threads);
        r.at_threshold = CountAll(assocs, t_op);
        ScoreMetricsAccumulator acc(options.calibration_bins, options.distance_bin_m,
                                    options.max_distance_m);
        for (size_t f = 0; f < frames.size(); ++f) acc.Add(frames[f], cfs[f], assocs[f]);
        r.brier = acc.Brier();
        r.calibration = acc.Calibration();
        r.localization = acc.Localization();

        if (!options.filter.empty()) {
          FilteredStats fs;
          fs.stable = CountStable(frames, cfs, assocs, options.filter.conditions, t_op);
          fs.naive = CountAll(AssociateAll(options.matcher, struck_cfs, difficulty, t_op, threads), t_op);
          r.filtered = fs;
        }
        result.results.push_back(std::move(r));
      }
    }
  }
  result.seconds = timer.ElapsedSeconds();
  return result;
}

std::vector<SweepRow> FilterSweep(const std::vector<EvalFrame>& frames, const EvalOptions& options,
                                  FilterBound bound, double from, double to, double step) {
  options.Check();
  STEREODET_CHECK(step > 0 && std::isfinite(from) && std::isfinite(to) && from <= to)
      << "sweep needs from <= to and step > 0, got from " << from << " to " << to << " step " << step;
  const int num_values = static_cast<int>(std::floor((to - from) / step + 1e-9)) + 1;
  STEREODET_CHECK(num_values <= 100000) << "sweep has too many values: " << num_values;
  const int threads = options.num_threads;
  const double t_op = options.score_threshold;
  std::vector<SweepRow> rows;
  for (const ClassSpec& spec : options.classes) {
    for (const OverlapKind kind : options.metrics) {
      const std::vector<ClassFrame> cfs = PrepareAll(frames, spec, kind, threads);
      for (const Difficulty difficulty : options.difficulties) {
        const std::vector<FrameAssociation> assocs =
            AssociateAll(options.matcher, cfs, difficulty, t_op, threads);
        for (int v = 0; v < num_values; ++v) {
          const double value = from + v * step;
          std::vector<FilterCondition> conditions = options.filter.conditions;
          conditions.push_back(FilterCondition{bound, value});
          SweepRow row;
          row.class_name = spec.name;
          row.metric = kind;
          row.difficulty = difficulty;
          row.value = value;
          row.stats.stable = CountStable(frames, cfs, assocs, conditions, t_op);
          const std::vector<ClassFrame> struck_cfs =
              PrepareAll(StrikeFailing(frames, conditions, threads), spec, kind, threads);
          row.stats.naive =
              CountAll(AssociateAll(options.matcher, struck_cfs, difficulty, t_op, threads), t_op);
          rows.push_back(std::move(row));
        }
      }
    }
  }
  return rows;
}

}  // namespace stereodet
