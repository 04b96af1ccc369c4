#include "stereodet/eval/evaluator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/curve_events_internal.h"
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

// ParallelFor over blocks of kFrameBlock consecutive frames, fn(i) for each frame i in order within
// a block: most frames take well under a microsecond per cell, so one task per frame would cost
// more in scheduling than in work.
constexpr size_t kFrameBlock = 64;
template <typename Fn>
void ForEachFrame(size_t num_frames, int num_threads, const Fn& fn) {
  ParallelFor((num_frames + kFrameBlock - 1) / kFrameBlock,
              [&](size_t b) {
                for (size_t i = b * kFrameBlock; i < std::min(num_frames, (b + 1) * kFrameBlock);
                     ++i)
                  fn(i);
              },
              num_threads);
}

// KITTI mode decides with the devkit's own overlap values where they may differ from ours; the
// optimal and VOC matchers (>= tau, the paper's definition) keep the exact ones.
// With --compat openpcdet, OpenPCDet's rules and overlaps instead (openpcdet_compat.h).
// `reuse`: the ClassFrames of the previous class or overlap kind, whose memory is reused.
// `after(i, frame)` is called on each prepared frame in the same pass (KittiPasses::CollectFrame).
// `reuse_selection`: `reuse` holds these frames' ClassFrames of `spec` for another overlap kind
// (PrepareClassFrame keeps their labels and detections; not with --compat openpcdet).
struct NoFrameWork {
  void operator()(size_t, const ClassFrame&) const {}
};
// `options`: the matcher, compat, LET tolerance and threads.
template <typename AfterFrame = NoFrameWork>
std::vector<ClassFrame> PrepareAll(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                                   OverlapKind kind, const EvalOptions& options,
                                   std::vector<ClassFrame> reuse = {},
                                   const AfterFrame& after = AfterFrame{},
                                   bool reuse_selection = false) {
  const OverlapArithmetic arithmetic =
      options.matcher == Matcher::kKitti ? OverlapArithmetic::kDevkit : OverlapArithmetic::kExact;
  const EvalCompat compat = options.compat;
  std::vector<ClassFrame> out = std::move(reuse);
  reuse_selection = reuse_selection && out.size() == frames.size();
  out.resize(frames.size());
  ForEachFrame(frames.size(), options.num_threads, [&](size_t i) {
    if (compat == EvalCompat::kOpenPcdet) {
      out[i] = PrepareClassFrameOpenPcdet(frames[i], spec, kind, std::move(out[i]));
    } else {
      PrepareClassFrameInPlace(frames[i], spec, kind, arithmetic, reuse_selection, &out[i],
                               options.let);
    }
    after(i, out[i]);
  });
  return out;
}

// The frames with the labels and detections `keep(object, is_label)` refuses struck (DontCare
// regions stay).
template <typename Keep>
std::vector<EvalFrame> StrikeFrames(const std::vector<EvalFrame>& frames, const Keep& keep,
                                    int num_threads) {
  std::vector<EvalFrame> out(frames.size());
  ParallelFor(
      frames.size(),
      [&](size_t i) {
        out[i].id = frames[i].id;
        for (const Object& label : frames[i].labels) {
          if (EqualsIgnoreCase(label.type, "DontCare") || keep(label, true)) {
            out[i].labels.push_back(label);
          }
        }
        for (const Object& det : frames[i].detections) {
          if (keep(det, false)) out[i].detections.push_back(det);
        }
      },
      num_threads);
  return out;
}

// The frames with the labels and detections that fail `conditions` struck.
std::vector<EvalFrame> StrikeFailing(const std::vector<EvalFrame>& frames,
                                     const std::vector<FilterCondition>& conditions,
                                     int num_threads) {
  return StrikeFrames(
      frames, [&](const Object& o, bool is_label) { return PassesFilter(o, is_label, conditions); },
      num_threads);
}

// The frames of breakdown bin [lower, upper) of `axis`, the naive way: labels and detections
// outside it struck, a detection without a value on the axis kept (it may be in the bin).
std::vector<EvalFrame> StrikeOutsideBin(const std::vector<EvalFrame>& frames, BreakdownAxis axis,
                                        double lower, double upper, int num_threads) {
  return StrikeFrames(
      frames,
      [&](const Object& o, bool is_label) {
        const std::optional<double> v = BreakdownValue(axis, o, is_label);
        return !v.has_value() || (*v >= lower && *v < upper);
      },
      num_threads);
}

// `reuse`: associations whose memory is reused (those of the previous cell).
std::vector<FrameAssociation> AssociateAll(Matcher matcher, const std::vector<ClassFrame>& cfs,
                                           Difficulty difficulty, double threshold, int num_threads,
                                           std::vector<FrameAssociation> reuse = {}) {
  std::vector<FrameAssociation> out = std::move(reuse);
  out.resize(cfs.size());
  ForEachFrame(cfs.size(), num_threads, [&](size_t i) {
    out[i] = Associate(matcher, cfs[i], difficulty, threshold, std::move(out[i]));
  });
  return out;
}

// AssociateAll for each of `difficulties` (out[d][frame]), each frame's together, and
// `before(i, cfs[i])` on each frame in the same pass (KittiPasses::CountFrame).
template <typename BeforeFrame = NoFrameWork>
std::vector<std::vector<FrameAssociation>> AssociateAll(
    Matcher matcher, const std::vector<ClassFrame>& cfs,
    const std::vector<Difficulty>& difficulties, double threshold, int num_threads,
    std::vector<std::vector<FrameAssociation>> reuse = {},
    const BeforeFrame& before = BeforeFrame{}) {
  std::vector<std::vector<FrameAssociation>> out = std::move(reuse);
  out.resize(difficulties.size());
  for (std::vector<FrameAssociation>& a : out) a.resize(cfs.size());
  ForEachFrame(cfs.size(), num_threads, [&](size_t i) {
    before(i, cfs[i]);
    for (size_t d = 0; d < difficulties.size(); ++d) {
      out[d][i] = Associate(matcher, cfs[i], difficulties[d], threshold, std::move(out[d][i]));
    }
  });
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

// The stable counts at the operating point: the unfiltered association, kept as `selection` says
// (the stable filter: pairs whose both sides pass, unmatched labels / detections that pass; a
// breakdown bin: breakdown.h).
OperatingPoint CountStable(const std::vector<EvalFrame>& frames, const std::vector<ClassFrame>& cfs,
                           const std::vector<FrameAssociation>& assocs,
                           const StableSelection& selection, double threshold) {
  int64_t tp = 0, fp = 0, fn = 0;
  for (size_t f = 0; f < frames.size(); ++f) {
    const Tally t = TallyAssociation(frames[f], cfs[f], assocs[f], &selection);
    tp += t.tp;
    fp += t.fp;
    fn += t.fn;
  }
  return MakeOperatingPoint(threshold, tp, fp, fn);
}

// An exact curve and its summaries.
FilteredCurve SummarizeExact(std::vector<CurvePoint> curve, bool with_aos) {
  FilteredCurve c;
  c.curve = std::move(curve);
  c.ap_r40 = InterpolatedApR40(c.curve);
  c.ap_r11 = InterpolatedApR11(c.curve);
  c.ap_voc = EveryPointAp(c.curve);
  c.aos_r40 = with_aos ? InterpolatedAosR40(c.curve) : kNaN;
  c.aos_r11 = with_aos ? InterpolatedAosR11(c.curve) : kNaN;
  return c;
}

struct ExactCurveResult {
  FilteredCurve curve;
  int64_t num_valid_labels = 0;
  std::vector<FilteredCurve> bins;  // with `bin_masks`: each bin's stable curve
};

// Curve and AP of the optimal or VOC matcher, exact at every score. AOS: VOC's pairs never change
// as the threshold drops, so its events carry the similarity; the optimal association may re-pair
// labels when a detection arrives, so its similarity is taken from the association at each score.
// With `assocs` (optimal matcher only; one per frame, their memory reused), each frame's
// association at `threshold` is written there too, from the overlap graph its curve events are
// computed on. With `bin_masks` (each frame's masks of `num_bins` breakdown bins), the bins' stable
// curves too, from the association at each distinct score of a frame, on the same graph.
ExactCurveResult ExactCurve(Matcher matcher, const std::vector<EvalFrame>& frames,
                            const std::vector<ClassFrame>& cfs, Difficulty difficulty,
                            bool with_aos, int num_threads,
                            std::vector<FrameAssociation>* assocs = nullptr, double threshold = 0.0,
                            const std::vector<BinMasks>* bin_masks = nullptr, size_t num_bins = 0) {
  // Per block of frames, the events in frame order (and each bin's): the blocks in order give
  // them in frame order, as one list per frame would.
  struct Block {
    std::vector<CurveEvent> events;
    int64_t num_labels = 0;
    std::vector<std::vector<CurveEvent>> bin_events;
    std::vector<int64_t> bin_labels;  // each bin's FN with no detection taken
  };
  const size_t n_s = bin_masks != nullptr ? num_bins : 0;
  const size_t num_blocks = (cfs.size() + kFrameBlock - 1) / kFrameBlock;
  std::vector<Block> blocks(num_blocks);
  ParallelFor(
      num_blocks,
      [&](size_t b) {
        Block& block = blocks[b];
        block.bin_events.resize(n_s);
        for (std::vector<CurveEvent>& e : block.bin_events) e.reserve(kFrameBlock);
        block.bin_labels.assign(n_s, 0);
        for (size_t i = b * kFrameBlock; i < std::min(cfs.size(), (b + 1) * kFrameBlock); ++i) {
          const ClassFrame& cf = cfs[i];
          block.num_labels += CountValidLabels(cf, difficulty);
          auto bins = [&](const FrameAssociator& associator) {
            if (n_s == 0) return;
            AppendAssociationEvents(associator, cf, difficulty, (*bin_masks)[i], n_s, with_aos,
                                    block.bin_events.data(), block.bin_labels.data());
          };
          if (matcher == Matcher::kOptimal) {
            // The frame's curve events, its operating point and its bins' events on one graph;
            // then its similarity events (which build their components' graphs).
            const OptimalAssociator associator(cf, difficulty);
            associator.AppendFrameEvents(&block.events);
            if (assocs != nullptr) (*assocs)[i] = associator.At(threshold, std::move((*assocs)[i]));
            bins(FrameAssociator(associator, difficulty));
            if (with_aos) {
              block.events =
                  OptimalSimilarityEvents(frames[i], cf, difficulty, std::move(block.events));
            }
          } else {
            block.events = VocFrameEvents(cf, difficulty, std::move(block.events));
            bins(FrameAssociator(matcher, cf, difficulty));
          }
        }
      },
      num_threads);
  ExactCurveResult result;
  std::vector<CurveEvent> events;
  size_t num_events = 0;
  for (const Block& block : blocks) num_events += block.events.size();
  events.reserve(num_events);
  for (const Block& block : blocks) {
    result.num_valid_labels += block.num_labels;
    events.insert(events.end(), block.events.begin(), block.events.end());
  }
  result.curve = SummarizeExact(BuildCurve(std::move(events), result.num_valid_labels), with_aos);
  for (size_t s = 0; s < n_s; ++s) {
    size_t num_events = 0;
    int64_t num_labels = 0;
    for (const Block& block : blocks) {
      num_events += block.bin_events[s].size();
      num_labels += block.bin_labels[s];
    }
    std::vector<CurveEvent> bin_events;
    bin_events.reserve(num_events);
    for (const Block& block : blocks) {
      bin_events.insert(bin_events.end(), block.bin_events[s].begin(), block.bin_events[s].end());
    }
    result.bins.push_back(SummarizeExact(BuildCurve(std::move(bin_events), num_labels), with_aos));
  }
  return result;
}

// The stable filter's exact curve (optimal / VOC): the unfiltered association at every score.
FilteredCurve StableExactCurve(Matcher matcher, const std::vector<EvalFrame>& frames,
                               const std::vector<ClassFrame>& cfs, Difficulty difficulty,
                               const StableSelection& selection, bool with_aos, int num_threads) {
  std::vector<std::vector<CurveEvent>> frame_events(cfs.size());
  std::vector<int64_t> base_fn(cfs.size(), 0);
  ParallelFor(
      cfs.size(),
      [&](size_t i) {
        FrameCurveEvents e =
            AssociationEvents(matcher, frames[i], cfs[i], difficulty, &selection, with_aos);
        frame_events[i] = std::move(e.events);
        base_fn[i] = e.base_fn;
      },
      num_threads);
  std::vector<CurveEvent> events;
  int64_t num_labels = 0;
  for (size_t i = 0; i < cfs.size(); ++i) {
    num_labels += base_fn[i];
    events.insert(events.end(), frame_events[i].begin(), frame_events[i].end());
  }
  return SummarizeExact(BuildCurve(std::move(events), num_labels), with_aos);
}

// The masks of `selections` on every frame (selection_mask_internal.h), made once per cell for
// all its difficulties and passes.
std::vector<BinMasks> MaskAll(const std::vector<EvalFrame>& frames,
                              const std::vector<ClassFrame>& cfs,
                              const std::vector<StableSelection>& selections, int num_threads) {
  std::vector<BinMasks> masks(cfs.size());
  ParallelFor(
      cfs.size(), [&](size_t i) { masks[i] = MaskBins(frames[i], cfs[i], selections); },
      num_threads);
  return masks;
}

// A stable selection's curve with the KITTI matcher from its pass 2 counts at the unfiltered
// evaluation's thresholds: the devkit's 41-slot arithmetic (KittiSlots: NaN for 0 / 0 kept,
// envelope, AP_R40 / AP_R11). With `empty_slots_zero` (breakdown bins) a threshold at which the
// selection holds no detection has precision 0 instead of NaN: a bin's labels that nothing finds
// above it score 0, where NaN would spread through the envelope to the whole AP.
FilteredCurve KittiSelectionCurve(const std::vector<double>& thresholds,
                                  const std::vector<KittiCounts>& counts, bool with_aos,
                                  bool empty_slots_zero) {
  FilteredCurve c;
  for (size_t t = 0; t < counts.size(); ++t) {
    CurvePoint p;
    p.threshold = thresholds[t];
    p.tp = counts[t].tp;
    p.fp = counts[t].fp;
    p.fn = counts[t].fn;
    p.similarity = counts[t].similarity;
    c.curve.push_back(FinishPoint(p));
  }
  std::array<double, kKittiSamplePoints> precision, aos;
  KittiSlots(counts, EvalCompat::kDevkit, empty_slots_zero, &precision, &aos);
  c.ap_r40 = KittiApR40(precision);
  c.ap_r11 = KittiApR11(precision);
  c.ap_voc = kNaN;
  c.aos_r40 = with_aos ? KittiApR40(aos) : kNaN;
  c.aos_r11 = with_aos ? KittiApR11(aos) : kNaN;
  return c;
}

// The stable filter's curve with the KITTI matcher (`masks` of the filter on each frame): the
// devkit's pass 2 association of the unfiltered set at the unfiltered evaluation's thresholds,
// counted under the filter (KittiPasses with the filter as its one bin; the breakdown bins are
// counted in the cell's own pass 2).
FilteredCurve StableKittiCurve(const std::vector<ClassFrame>& cfs, Difficulty difficulty,
                               const std::vector<double>& thresholds,
                               const std::vector<BinMasks>& masks, bool with_aos, int num_threads) {
  KittiPasses passes(cfs.size(), {difficulty});
  passes.UseThresholds({thresholds});
  passes.SetBins(&masks, 1);
  ForEachFrame(cfs.size(), num_threads, [&](size_t i) { passes.CountFrame(i, cfs[i]); });
  return KittiSelectionCurve(thresholds, passes.Finish()[0].bin_counts[0], with_aos,
                             /*empty_slots_zero=*/false);
}

// The rows of one frame (see MatchRecord), in the documented order.
std::vector<MatchRecord> FrameRecords(int32_t frame_index, const EvalFrame& frame,
                                      const ClassFrame& cf, const FrameAssociation& a,
                                      OverlapKind kind, Difficulty difficulty, double threshold,
                                      const LetOptions& let) {
  std::vector<MatchRecord> rows;
  std::vector<MatchRecord>* out = &rows;
  auto overlap = [&](int j, int i) {
    return MatchOverlap(kind, frame.detections[cf.det_object[j]], frame.labels[cf.label_object[i]],
                        let);
  };
  auto pair_overlap = [&](int i, int j) {
    const int e = cf.FindEdge(i, j);
    return e >= 0 ? KittiRecordedOverlap(kind, frame, cf, i, e) : overlap(j, i);
  };
  for (int j = 0; j < cf.num_dets(); ++j) {
    if (a.det_outcome[j] == Outcome::kNone) continue;
    MatchRecord r;
    r.frame = frame_index;
    r.detection = cf.det_object[j];
    r.outcome = a.det_outcome[j];
    if (r.outcome == Outcome::kTp) {
      r.label = cf.label_object[a.det_label[j]];
      r.label_valid = true;
      r.iou = pair_overlap(a.det_label[j], j);
    } else {
      for (int i = 0; i < cf.num_labels(); ++i) r.iou = std::max(r.iou, overlap(j, i));
    }
    out->push_back(r);
  }
  for (int i = 0; i < cf.num_labels(); ++i) {
    if (a.label_outcome[i] == Outcome::kTp) continue;
    MatchRecord r;
    r.frame = frame_index;
    r.label = cf.label_object[i];
    r.outcome = a.label_outcome[i];
    r.label_valid = cf.LabelValid(i, difficulty);
    for (int j = 0; j < cf.num_dets(); ++j) {
      if (!cf.det_is_class[j] || cf.det_score[j] < threshold) continue;
      r.iou = std::max(r.iou, overlap(j, i));
    }
    out->push_back(r);
  }
  return rows;
}

std::vector<MatchRecord> BuildRecords(const std::vector<EvalFrame>& frames,
                                      const std::vector<ClassFrame>& cfs,
                                      const std::vector<FrameAssociation>& assocs, OverlapKind kind,
                                      Difficulty difficulty, double threshold,
                                      const LetOptions& let, int num_threads) {
  std::vector<std::vector<MatchRecord>> per_frame(frames.size());
  ParallelFor(
      frames.size(),
      [&](size_t f) {
        per_frame[f] = FrameRecords(static_cast<int32_t>(f), frames[f], cfs[f], assocs[f], kind,
                                    difficulty, threshold, let);
      },
      num_threads);
  size_t total = 0;
  for (const auto& v : per_frame) total += v.size();
  std::vector<MatchRecord> out;
  out.reserve(total);
  for (const auto& v : per_frame) out.insert(out.end(), v.begin(), v.end());
  return out;
}

// A LET cell's TP-weighted AP, made in the AOS channel (the TP weight is the affinity there:
// ClassFrame::TpWeight), is its LET-APL: moved to the apl fields, AOS left NaN.
void UseWeightedApAsApl(ClassResult* r) {
  const auto move = [](FilteredCurve* c) {
    c->apl_r40 = c->aos_r40;
    c->apl_r11 = c->aos_r11;
    c->aos_r40 = c->aos_r11 = kNaN;
  };
  r->apl_r40 = r->aos_r40;
  r->apl_r11 = r->aos_r11;
  r->aos_r40 = r->aos_r11 = kNaN;
  r->has_apl = r->has_aos;
  r->has_aos = false;
  r->kitti_apl = std::move(r->kitti_aos);
  r->kitti_aos.clear();
  if (r->filtered) {
    move(&r->filtered->naive_curve);
    move(&r->filtered->stable_curve);
  }
  for (BreakdownBin& bin : r->breakdown) {
    move(&bin.curve);
    if (bin.naive) move(&bin.naive->curve);
  }
}

// `r` with the KITTI matcher's curve and summaries.
ClassResult WithKittiCurve(const KittiClassResult& k, bool with_aos, ClassResult result) {
  ClassResult* r = &result;
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
    p.similarity = k.counts[t].similarity;
    p = FinishPoint(p);
    r->curve.push_back(p);
  }
  return result;
}

ClassResult KittiCurve(const std::vector<ClassFrame>& cfs, Difficulty difficulty, bool with_aos,
                       int num_threads, EvalCompat compat = EvalCompat::kDevkit) {
  return WithKittiCurve(EvaluateKittiClass(cfs, difficulty, num_threads, compat), with_aos, {});
}

// A set's own curve, as an unfiltered cell gets it: the devkit's with the KITTI matcher (its own
// thresholds; no AP_VOC), the exact one with the others. For the naive filter and naive bins.
ExactCurveResult OwnCurve(Matcher matcher, const std::vector<EvalFrame>& frames,
                          const std::vector<ClassFrame>& cfs, Difficulty difficulty, bool with_aos,
                          int num_threads, EvalCompat compat) {
  if (matcher != Matcher::kKitti) {
    return ExactCurve(matcher, frames, cfs, difficulty, with_aos, num_threads);
  }
  ClassResult own = KittiCurve(cfs, difficulty, with_aos, num_threads, compat);
  ExactCurveResult out;
  out.num_valid_labels = own.num_valid_labels;
  out.curve.curve = std::move(own.curve);
  out.curve.ap_r40 = own.ap_r40;
  out.curve.ap_r11 = own.ap_r11;
  out.curve.ap_voc = kNaN;
  out.curve.aos_r40 = own.aos_r40;
  out.curve.aos_r11 = own.aos_r11;
  return out;
}

ScoreSummary SummarizeScores(const std::vector<EvalFrame>& frames) {
  ScoreSummary s;
  s.min_score = std::numeric_limits<double>::infinity();
  s.max_score = -std::numeric_limits<double>::infinity();
  for (const EvalFrame& f : frames) {
    for (const Object& d : f.detections) {
      const double score = d.score.value_or(0.0);
      ++s.num_scores;
      s.num_outside_unit += score < 0 || score > 1 ? 1 : 0;
      s.min_score = std::min(s.min_score, score);
      s.max_score = std::max(s.max_score, score);
    }
  }
  if (s.num_scores == 0) s.min_score = s.max_score = kNaN;
  return s;
}

}  // namespace

const ClassResult* EvalResult::Find(const std::string& class_name, OverlapKind metric,
                                    Difficulty difficulty) const {
  for (const ClassResult& r : results) {
    if (EqualsIgnoreCase(r.class_name, class_name) && r.metric == metric &&
        r.difficulty == difficulty) {
      return &r;
    }
  }
  return nullptr;
}

EvalResult Evaluate(const std::vector<EvalFrame>& frames, const EvalOptions& options) {
  options.Check();
  const Timer timer;
  EvalResult result;
  result.num_frames = static_cast<int64_t>(frames.size());
  const EvalCompat compat = options.compat;
  result.aos_computed =
      options.compute_aos &&
      (compat == EvalCompat::kOpenPcdet ? OpenPcdetComputesAos(frames) : AllAlphasValid(frames));
  const int threads = options.num_threads;
  const double t_op = options.score_threshold;
  result.scores = SummarizeScores(frames);
  result.probability_metrics =
      options.score_transform != ScoreTransform::kNone || result.scores.num_outside_unit == 0;

  std::vector<EvalFrame> struck;
  if (!options.filter.empty()) struck = StrikeFailing(frames, options.filter.conditions, threads);
  // With breakdown_naive, each bin's frames (in the order of the cells' breakdown bins).
  std::vector<std::vector<EvalFrame>> bin_frames;
  if (options.breakdown_naive) {
    for (const BreakdownOptions& breakdown : options.breakdowns) {
      for (int b = 0; b < breakdown.num_bins(); ++b) {
        bin_frames.push_back(StrikeOutsideBin(frames, breakdown.axis, breakdown.edges[b],
                                              breakdown.edges[b + 1], threads));
      }
    }
  }

  // Kept from cell to cell so that their memory is reused; and from one overlap kind of a class to
  // the next, their labels and detections (the class whose ClassFrames they hold).
  std::vector<ClassFrame> cfs, struck_cfs;
  const ClassSpec* cfs_class = nullptr;
  const ClassSpec* struck_cfs_class = nullptr;
  std::vector<std::vector<FrameAssociation>> assocs;  // by difficulty, then frame
  // What depends only on a class's labels and detections, not on the overlap kind: made at the
  // class's first kind and kept for the others while `cfs` keeps its selection (see below).
  std::vector<StableSelection> bins;
  for (const BreakdownOptions& breakdown : options.breakdowns) {
    for (int b = 0; b < breakdown.num_bins(); ++b) {
      bins.push_back(
          StableSelection::Bin(breakdown.axis, breakdown.edges[b], breakdown.edges[b + 1]));
    }
  }
  std::vector<BinMasks> bin_masks;                            // the bins' masks on every frame
  std::vector<size_t> dece_first;                             // frame f's first D-ECE cell
  std::vector<ScoreMetricsAccumulator::DeceCell> dece_cells;  // each detection's
  const std::vector<Difficulty>& difficulties = options.difficulties;
  const size_t n_d = difficulties.size();
  const bool kitti = options.matcher == Matcher::kKitti;
  for (const ClassSpec& spec : options.classes) {
    int64_t num_detections = 0;
    for (const EvalFrame& f : frames) {
      for (const Object& d : f.detections)
        num_detections += EqualsIgnoreCase(d.type, spec.name) ? 1 : 0;
    }
    for (const OverlapKind kind : options.metrics) {
      const bool evaluated = compat == EvalCompat::kOpenPcdet || !options.require_detections ||
                             HasEvaluableDetection(frames, spec, kind);
      // The difficulties of one class and overlap kind go phase by phase, every difficulty of a
      // frame at once: one pass over the frames' data per phase instead of one per difficulty.
      std::vector<ClassResult> cell(n_d);
      for (size_t d = 0; d < n_d; ++d) {
        ClassResult& r = cell[d];
        r.class_name = spec.name;
        r.metric = kind;
        r.difficulty = difficulties[d];
        r.min_overlap = spec.min_overlap[static_cast<int>(kind)];
        r.evaluated = evaluated;
        r.num_detections = num_detections;
        if (!evaluated) r.ap_r40 = r.ap_r11 = r.ap_voc = r.aos_r40 = r.aos_r11 = kNaN;
      }
      if (!evaluated) {
        for (ClassResult& r : cell) result.results.push_back(std::move(r));
        continue;
      }
      // The TP-weighted AP: AOS in 2D (as the devkit), LET-APL in the LET kinds (their weight, the
      // affinity, needs no alpha); moved to ClassResult::apl_* at the end (UseWeightedApAsApl).
      const bool with_aos = (result.aos_computed && kind == OverlapKind::k2D) || IsLetKind(kind);
      // KITTI matcher: its pass 1 goes with the preparation of each frame and its pass 2 with the
      // association at the operating point (kitti_passes.Finish() below).
      static_assert(kFrameBlock == KittiPasses::kBlock);
      KittiPasses kitti_passes(kitti ? frames.size() : 0, difficulties, compat);
      if (kitti) {
        cfs = PrepareAll(
            frames, spec, kind, options, std::move(cfs),
            [&](size_t i, const ClassFrame& cf) { kitti_passes.CollectFrame(i, cf); },
            cfs_class == &spec);
        kitti_passes.ChooseThresholds();
      } else {
        cfs = PrepareAll(frames, spec, kind, options, std::move(cfs), NoFrameWork{},
                         cfs_class == &spec);
      }
      // PrepareAll kept the previous kind's labels and detections (reuse_selection) unless this
      // is the class's first kind; OpenPCDet's preparation selects them anew each time.
      const bool same_objects = cfs_class == &spec && compat != EvalCompat::kOpenPcdet;
      cfs_class = &spec;
      if (!options.filter.empty()) {
        struck_cfs = PrepareAll(struck, spec, kind, options, std::move(struck_cfs), NoFrameWork{},
                                struck_cfs_class == &spec);
        struck_cfs_class = &spec;
      }

      // The breakdown bins' masks on every frame, for all difficulties and kinds of the class.
      if (!bins.empty() && !same_objects) bin_masks = MaskAll(frames, cfs, bins, threads);
      const size_t n_s = bins.size();
      // Each difficulty's bins' curves: made with the unfiltered curve (the KITTI matcher's bins
      // counted in its pass 2, the exact matchers' on the graph of their curve).
      std::vector<std::vector<FilteredCurve>> bin_curves(n_d);
      if (kitti && n_s > 0) kitti_passes.SetBins(&bin_masks, n_s);

      // The operating point's associations (and the KITTI matcher's pass 2). The optimal matcher's
      // are made with its curve below, on the same overlap graphs.
      const bool optimal = options.matcher == Matcher::kOptimal;
      if (optimal) {
        assocs.resize(n_d);
        for (std::vector<FrameAssociation>& a : assocs) a.resize(cfs.size());
      } else if (kitti) {
        assocs =
            AssociateAll(options.matcher, cfs, difficulties, t_op, threads, std::move(assocs),
                         [&](size_t i, const ClassFrame& cf) { kitti_passes.CountFrame(i, cf); });
      } else {
        assocs = AssociateAll(options.matcher, cfs, difficulties, t_op, threads, std::move(assocs));
      }

      // Curves.
      if (kitti) {
        const std::vector<KittiClassResult> curves = kitti_passes.Finish();
        for (size_t d = 0; d < n_d; ++d) {
          cell[d] = WithKittiCurve(curves[d], with_aos, std::move(cell[d]));
          for (const std::vector<KittiCounts>& counts : curves[d].bin_counts) {
            bin_curves[d].push_back(KittiSelectionCurve(curves[d].thresholds, counts, with_aos,
                                                        /*empty_slots_zero=*/true));
          }
        }
      } else {
        for (size_t d = 0; d < n_d; ++d) {
          ClassResult& r = cell[d];
          ExactCurveResult exact =
              ExactCurve(options.matcher, frames, cfs, difficulties[d], with_aos, threads,
                         optimal ? &assocs[d] : nullptr, t_op, &bin_masks, n_s);
          bin_curves[d] = std::move(exact.bins);
          r.num_valid_labels = exact.num_valid_labels;
          FilteredCurve& c = exact.curve;
          r.curve = std::move(c.curve);
          r.ap_r40 = c.ap_r40;
          r.ap_r11 = c.ap_r11;
          r.ap_voc = c.ap_voc;
          r.aos_r40 = c.aos_r40;
          r.aos_r11 = c.aos_r11;
          r.has_aos = with_aos;
        }
      }
      for (ClassResult& r : cell) r.best_f1 = BestF1(r.curve);

      // The operating point: counts and the metrics of scores, each accumulator over the frames in
      // order.
      std::vector<ScoreMetricsAccumulator> accs;
      std::vector<std::array<int64_t, 3>> tp_fp_fn(n_d, {0, 0, 0});
      for (size_t d = 0; d < n_d; ++d) {
        accs.emplace_back(options.calibration_bins, options.distance_bin_m, options.max_distance_m,
                          options.score_transform);
        accs.back().EnableDece(options.dece);
      }
      // Each detection's D-ECE cell (its score and 2D box), once for the class's kinds,
      // difficulties and bins.
      if (n_d > 0 && !same_objects) {
        dece_first.assign(frames.size() + 1, 0);
        for (size_t f = 0; f < frames.size(); ++f) {
          dece_first[f + 1] = dece_first[f] + static_cast<size_t>(cfs[f].num_dets());
        }
        dece_cells.resize(dece_first.back());
        ForEachFrame(frames.size(), threads, [&](size_t f) {
          accs[0].DeceCells(frames[f], cfs[f], dece_cells.data() + dece_first[f]);
        });
      }
      for (size_t f = 0; f < frames.size(); ++f) {
        for (size_t d = 0; d < n_d; ++d) {
          const FrameAssociation& a = assocs[d][f];
          tp_fp_fn[d][0] += a.CountDets(Outcome::kTp);
          tp_fp_fn[d][1] += a.CountDets(Outcome::kFp);
          tp_fp_fn[d][2] += a.CountLabels(Outcome::kFn);
          accs[d].Add(frames[f], cfs[f], a, difficulties[d], nullptr,
                      dece_cells.data() + dece_first[f]);
        }
      }
      for (size_t d = 0; d < n_d; ++d) {
        cell[d].at_threshold =
            MakeOperatingPoint(t_op, tp_fp_fn[d][0], tp_fp_fn[d][1], tp_fp_fn[d][2]);
      }

      for (size_t d = 0; d < n_d; ++d) {
        ClassResult& r = cell[d];
        const Difficulty difficulty = difficulties[d];
        r.brier = accs[d].Brier();
        r.calibration = accs[d].Calibration();
        if (!result.probability_metrics) {
          r.brier = WithoutProbabilities(r.brier);
          r.calibration = WithoutProbabilities(r.calibration);
        }
        r.localization = accs[d].Localization();
        if (options.keep_records) {
          r.records =
              BuildRecords(frames, cfs, assocs[d], kind, difficulty, t_op, options.let, threads);
        }

        if (!options.filter.empty()) {
          FilteredStats fs;
          const StableSelection filter = StableSelection::Filter(options.filter.conditions);
          fs.stable = CountStable(frames, cfs, assocs[d], filter, t_op);
          fs.naive =
              CountAll(AssociateAll(options.matcher, struck_cfs, difficulty, t_op, threads), t_op);
          // Naive curve: the struck set evaluated exactly like the unfiltered one.
          fs.naive_curve =
              OwnCurve(options.matcher, struck, struck_cfs, difficulty, with_aos, threads, compat)
                  .curve;
          fs.stable_curve =
              kitti ? StableKittiCurve(cfs, difficulty, r.kitti_thresholds,
                                       MaskAll(frames, cfs, {filter}, threads), with_aos, threads)
                    : StableExactCurve(options.matcher, frames, cfs, difficulty, filter, with_aos,
                                       threads);
          r.filtered = fs;
        }
        // Breakdowns: every bin from the cell's association, its masks made once per class; the
        // curves of all bins from one association per run of thresholds (KITTI) or per distinct
        // score (exact matchers: made with the unfiltered curve above).
        // The bins' valid labels, operating points and score metrics: one pass over the frames for
        // all bins (each bin's sums in frame order, whatever the threads).
        std::vector<BreakdownBin> bin_results(n_s);
        std::vector<Tally> bin_tallies(n_s);
        std::vector<ScoreMetricsAccumulator> bin_accs;
        for (size_t k = 0; k < n_s; ++k) {
          bin_accs.emplace_back(options.calibration_bins, options.distance_bin_m,
                                options.max_distance_m, options.score_transform);
          bin_accs.back().EnableDece(options.dece);
        }
        for (size_t f = 0; f < frames.size() && n_s > 0; ++f) {
          const ClassFrame& cf = cfs[f];
          if (cf.num_labels() == 0 && cf.num_dets() == 0) continue;
          const BinMasks& masks = bin_masks[f];
          for (int i = 0; i < cf.num_labels(); ++i) {
            if (!cf.LabelValid(i, difficulty)) continue;
            for (size_t k = 0; k < n_s; ++k) {
              bin_results[k].num_valid_labels += masks.Bin(k).KeepsLabel(i);
            }
          }
          TallyBins(cf, assocs[d][f], masks, n_s, bin_tallies.data());
          ScoreMetricsAccumulator::AddToBins(frames[f], cf, assocs[d][f], difficulty, masks, n_s,
                                             bin_accs.data(), dece_cells.data() + dece_first[f]);
        }
        for (size_t k = 0; k < n_s; ++k) {
          BreakdownBin& bin = bin_results[k];
          const Tally& t = bin_tallies[k];
          bin.at_threshold = MakeOperatingPoint(t_op, t.tp, t.fp, t.fn);
          const ScoreMetricsAccumulator& acc = bin_accs[k];
          bin.brier = result.probability_metrics ? acc.Brier() : WithoutProbabilities(acc.Brier());
          bin.calibration = result.probability_metrics ? acc.Calibration()
                                                       : WithoutProbabilities(acc.Calibration());
        }
        for (size_t k = 0; k < n_s; ++k) {
          const StableSelection& selection = bins[k];
          BreakdownBin bin = std::move(bin_results[k]);
          bin.axis = selection.axis;
          bin.lower = selection.lower;
          bin.upper = selection.upper;
          bin.curve = std::move(bin_curves[d][k]);
          if (bin.num_valid_labels == 0) {  // no label in the bin: no recall, AP undefined
            bin.curve.ap_r40 = bin.curve.ap_r11 = bin.curve.ap_voc = kNaN;
            bin.curve.aos_r40 = bin.curve.aos_r11 = kNaN;
          }
          if (options.breakdown_naive) {
            // The bin evaluated on its own, as an unfiltered cell is.
            const std::vector<ClassFrame> bin_cfs = PrepareAll(bin_frames[k], spec, kind, options);
            BreakdownBin::Naive naive;
            naive.at_threshold =
                CountAll(AssociateAll(options.matcher, bin_cfs, difficulty, t_op, threads), t_op);
            ExactCurveResult own = OwnCurve(options.matcher, bin_frames[k], bin_cfs, difficulty,
                                            with_aos, threads, compat);
            naive.num_valid_labels = own.num_valid_labels;
            naive.curve = std::move(own.curve);
            if (naive.num_valid_labels == 0) {
              naive.curve.ap_r40 = naive.curve.ap_r11 = naive.curve.ap_voc = kNaN;
              naive.curve.aos_r40 = naive.curve.aos_r11 = kNaN;
            }
            bin.naive = std::move(naive);
          }
          r.breakdown.push_back(std::move(bin));
        }
        if (IsLetKind(kind)) UseWeightedApAsApl(&r);
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
      << "sweep needs from <= to and step > 0, got from " << from << " to " << to << " step "
      << step;
  // Counted in double first: (to - from) / step can be far beyond an int (--step 1e-9), and the
  // cast of such a value is undefined (the audit saw a sweep of only a header, exit 0).
  const double values = std::floor((to - from) / step + 1e-9) + 1;
  STEREODET_CHECK(values <= 100000) << "sweep has too many values: " << values << " (from " << from
                                    << " to " << to << " step " << step << "; at most 100000)";
  const int num_values = static_cast<int>(values);
  const int threads = options.num_threads;
  const double t_op = options.score_threshold;
  std::vector<SweepRow> rows;
  for (const ClassSpec& spec : options.classes) {
    for (const OverlapKind kind : options.metrics) {
      const std::vector<ClassFrame> cfs = PrepareAll(frames, spec, kind, options);
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
          row.stats.stable =
              CountStable(frames, cfs, assocs, StableSelection::Filter(conditions), t_op);
          const std::vector<ClassFrame> struck_cfs =
              PrepareAll(StrikeFailing(frames, conditions, threads), spec, kind, options);
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
