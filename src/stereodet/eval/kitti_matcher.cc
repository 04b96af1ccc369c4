#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <utility>

#include "stereodet/eval/curve_events_internal.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/openpcdet_compat_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"

namespace stereodet {

namespace {

// The devkit's NO_DETECTION: in pass 1 a detection is chosen only if its score is above it.
constexpr double kNoDetection = -10000000;

// The devkit's ignored_det of each detection for `difficulty` (ClassFrame::det_state), read with a
// stride, so that the states ClassFrameBuilder derived are used in place.
class DetStateView {
 public:
  DetStateView(const int8_t* first, int stride) : first_(first), stride_(stride) {}
  int8_t operator[](int j) const { return first_[static_cast<ptrdiff_t>(j) * stride_]; }

 private:
  const int8_t* first_;
  int stride_;
};

// ClassFrame::det_state for `difficulty`: the frame's own, or, for a ClassFrame put together
// without it, derived into `scratch`: 1 if lower than the difficulty's minimum height (any class;
// the devkit truncates the height to an int, which for an integer minimum compares the same), else
// 0 for the class, -1 for other classes.
inline DetStateView DetStates(const ClassFrame& f, Difficulty difficulty,
                              std::vector<int8_t>* scratch) {
  const int n = f.num_dets();
  const int d = static_cast<int>(difficulty);
  if (f.det_state.size() == static_cast<size_t>(n) * kNumDifficulties) {
    return DetStateView(f.det_state.data() + d, kNumDifficulties);
  }
  const double min_height = KittiDifficultyLimits(difficulty).min_height_px;
  scratch->resize(n);
  int8_t* out = scratch->data();
  const double* height = f.det_height.data();
  const uint8_t* is_class = f.det_is_class.data();
  for (int j = 0; j < n; ++j)
    out[j] = std::trunc(height[j]) < min_height ? 1 : (is_class[j] ? 0 : -1);
  return DetStateView(out, 1);
}

// Memory reused by one thread from call to call: the functions below run once per frame, class,
// overlap kind and difficulty (tens of thousands of times per evaluation), mostly on frames of a
// few objects, where allocating these lists afresh cost more than the matching.
struct ThreadScratch {
  std::vector<int8_t> states;
  std::vector<uint8_t> assigned, interacting;
  std::vector<double> interacting_scores, free_fp_scores;
  // Breakdown bins' (AddFrameCounts with bins): the free FPs by descending score, the association,
  // each bin's tally of it and its free FPs so far.
  std::vector<int32_t> free_fp_dets;
  FrameAssociation association;
  std::vector<Tally> bin_tallies;
  std::vector<int64_t> bin_free_fp;
};

ThreadScratch& Scratch() {
  thread_local ThreadScratch scratch;
  return scratch;
}

// A ClassFrame's lists as plain pointers, read by the passes below. They write byte-sized lists
// (assigned, interacting, outcomes), which may alias anything; kept in a local view, the frame's
// sizes and list addresses stay in registers instead of being read again after each such write.
struct FrameView {
  explicit FrameView(const ClassFrame& f, Difficulty difficulty)
      : num_labels(f.num_labels()),
        num_dets(f.num_dets()),
        difficulty_bit(static_cast<uint8_t>(1u << static_cast<int>(difficulty))),
        tau(f.min_overlap),
        label_neighbour(f.label_neighbour.data()),
        label_difficulty(f.label_difficulty.data()),
        label_alpha(f.label_alpha.data()),
        det_score(f.det_score.data()),
        det_alpha(f.det_alpha.data()),
        det_dontcare(f.det_dontcare.data()),
        edge_begin(f.edge_begin.data()),
        edge_det(f.edge_det.data()),
        edge_overlap(f.edge_overlap.data()),
        edge_affinity(f.edge_affinity.empty() ? nullptr : f.edge_affinity.data()),
        num_edges(static_cast<int>(f.edge_det.size())) {}

  // ClassFrame::LabelValid
  bool LabelValid(int i) const {
    return !label_neighbour[i] && (label_difficulty[i] & difficulty_bit) != 0;
  }

  int num_labels, num_dets;
  uint8_t difficulty_bit;
  double tau;
  const uint8_t *label_neighbour, *label_difficulty;
  const double* label_alpha;
  const double *det_score, *det_alpha;
  const uint8_t* det_dontcare;
  const int32_t *edge_begin, *edge_det;
  const double* edge_overlap;
  const double* edge_affinity;  // LET kinds only, else null (ClassFrame::edge_affinity)
  int num_edges;
};

struct Pass2Result {
  int64_t tp = 0, fn = 0;
  double similarity = 0.0;
};

// computeStatistics(compute_fp = true) without the FP count: matches labels in order, each taking
// the unassigned detection (score >= threshold) with overlap > tau of largest overlap (for the LET
// kinds, of largest LET-IoU x affinity: ClassFrame::EdgeWeight); a valid detection replaces an
// earlier-chosen ignored one. Marks `assigned` and, if `assoc`, records pairs.
Pass2Result RunPass2(const FrameView& f, DetStateView states, double threshold,
                     std::vector<uint8_t>* assigned_list, FrameAssociation* assoc) {
  Pass2Result r;
  const double tau = f.tau;
  assigned_list->assign(f.num_dets, 0);
  uint8_t* const assigned = assigned_list->data();
  for (int i = 0; i < f.num_labels; ++i) {
    const bool label_valid = f.LabelValid(i);
    int best = -1, best_edge = -1;
    double max_overlap = 0.0;
    bool assigned_ignored = false;
    for (int e = f.edge_begin[i], end = f.edge_begin[i + 1]; e < end; ++e) {
      const int j = f.edge_det[e];
      const int8_t state = states[j];
      if (state == -1 || assigned[j] || f.det_score[j] < threshold) continue;
      const double overlap = f.edge_overlap[e];
      if (!(overlap > tau)) continue;
      const double weight = f.edge_affinity ? overlap * f.edge_affinity[e] : overlap;
      if (state == 0 && (weight > max_overlap || assigned_ignored)) {
        max_overlap = weight;
        best = j;
        best_edge = e;
        assigned_ignored = false;
      } else if (best < 0 && state == 1) {
        best = j;
        best_edge = e;
        assigned_ignored = true;
      }
    }
    if (best < 0) {
      if (label_valid) {
        ++r.fn;
        if (assoc) assoc->label_outcome[i] = Outcome::kFn;
      }
    } else if (!label_valid || states[best] == 1) {
      assigned[best] = 1;
    } else {
      ++r.tp;
      r.similarity += f.edge_affinity
                          ? f.edge_affinity[best_edge]
                          : (1.0 + std::cos(f.label_alpha[i] - f.det_alpha[best])) / 2.0;
      assigned[best] = 1;
      if (assoc) {
        assoc->label_outcome[i] = Outcome::kTp;
        assoc->label_det[i] = best;
        assoc->det_outcome[best] = Outcome::kTp;
        assoc->det_label[best] = i;
      }
    }
  }
  return r;
}

}  // namespace

std::vector<double> KittiThresholds(std::vector<double> v, double n_groundtruth) {
  std::vector<double> t;
  std::sort(v.begin(), v.end(), std::greater<double>());
  double current_recall = 0;
  const size_t n = v.size();
  for (size_t i = 0; i < n; ++i) {
    const double l_recall = static_cast<double>(i + 1) / n_groundtruth;
    const double r_recall = i + 1 < n ? static_cast<double>(i + 2) / n_groundtruth : l_recall;
    if ((r_recall - current_recall) < (current_recall - l_recall) && i + 1 < n) continue;
    t.push_back(v[i]);
    current_recall += 1.0 / (kKittiSamplePoints - 1.0);
  }
  return t;
}

KittiTpScores KittiCollectTpScores(const ClassFrame& frame, Difficulty difficulty,
                                   std::vector<double> append_to) {
  KittiTpScores out;
  out.scores = std::move(append_to);
  std::vector<double>* tp_scores = &out.scores;
  ThreadScratch& scratch = Scratch();
  const DetStateView states = DetStates(frame, difficulty, &scratch.states);
  const FrameView f(frame, difficulty);
  scratch.assigned.assign(f.num_dets, 0);
  uint8_t* const assigned = scratch.assigned.data();
  const double tau = f.tau;
  int n_gt = 0;
  for (int i = 0; i < f.num_labels; ++i) {
    const bool label_valid = f.LabelValid(i);
    n_gt += label_valid ? 1 : 0;
    int best = -1;
    double best_score = kNoDetection;
    for (int e = f.edge_begin[i], end = f.edge_begin[i + 1]; e < end; ++e) {
      const int j = f.edge_det[e];
      if (states[j] == -1 || assigned[j]) continue;
      if (f.edge_overlap[e] > tau && f.det_score[j] > best_score) {
        best = j;
        best_score = f.det_score[j];
      }
    }
    if (best < 0) continue;
    assigned[best] = 1;
    if (label_valid && states[best] == 0) tp_scores->push_back(f.det_score[best]);
  }
  out.num_groundtruth = n_gt;
  return out;
}

namespace {

// A frame's breakdown bins in AddFrameCounts: its masks of `num_bins` bins, and each bin's counts
// (counts[s], s < num_bins).
struct FrameBins {
  const BinMasks* masks;
  size_t num_bins;
  PassTwoCounts* counts;
};

// Pass 2 of one frame at every threshold, added to *counts; with `bins`, each bin's counts of the
// same associations added to bins->counts[s], as TallyBins counts KittiAssociate's association at
// each threshold.
void AddFrameCounts(const ClassFrame& frame, Difficulty difficulty,
                    const std::vector<double>& thresholds, PassTwoCounts* counts,
                    const FrameBins* bins = nullptr) {
  const size_t n_t = thresholds.size();
  const FrameView f(frame, difficulty);
  int64_t n_valid = 0;
  for (int i = 0; i < f.num_labels; ++i) n_valid += f.LabelValid(i) ? 1 : 0;
  ThreadScratch& scratch = Scratch();
  const size_t n_s = bins != nullptr ? bins->num_bins : 0;
  std::vector<Tally>& bin_tallies = scratch.bin_tallies;
  if (n_s > 0) {
    // Before any detection takes part: each bin's valid labels are FN.
    bin_tallies.assign(n_s, Tally{});
    TallyNoDetections(frame, difficulty, *bins->masks, n_s, bin_tallies.data());
  }
  if (f.num_dets == 0) {  // many frames hold nothing of a class: every valid label is a FN
    if (n_t > 0) {
      counts->AddRun(0, n_t, 0, 0, n_valid, 0.0);
      for (size_t s = 0; s < n_s; ++s) bins->counts[s].AddRun(0, n_t, 0, 0, bin_tallies[s].fn, 0.0);
    }
    return;
  }
  const DetStateView states = DetStates(frame, difficulty, &scratch.states);
  const double tau = f.tau;
  // Detections that can be chosen by some label; only their presence above the threshold changes
  // the greedy's outcome. The others are FPs (valid, not in DontCare) or nothing.
  scratch.interacting.assign(f.num_dets, 0);
  uint8_t* const interacting = scratch.interacting.data();
  for (int e = 0; e < f.num_edges; ++e) {
    const int j = f.edge_det[e];
    if (states[j] != -1 && f.edge_overlap[e] > tau) interacting[j] = 1;
  }
  std::vector<double>& interacting_scores = scratch.interacting_scores;
  std::vector<double>& free_fp_scores = scratch.free_fp_scores;
  std::vector<int32_t>& free_fp_dets = scratch.free_fp_dets;
  interacting_scores.clear();
  free_fp_scores.clear();
  free_fp_dets.clear();
  for (int j = 0; j < f.num_dets; ++j) {
    if (interacting[j]) {
      interacting_scores.push_back(f.det_score[j]);
    } else if (states[j] == 0 && !f.det_dontcare[j]) {
      free_fp_scores.push_back(f.det_score[j]);
      if (n_s > 0) free_fp_dets.push_back(j);
    }
  }
  std::sort(interacting_scores.begin(), interacting_scores.end(), std::greater<double>());
  std::sort(free_fp_scores.begin(), free_fp_scores.end(), std::greater<double>());
  // (The same order of scores: the first k of each list are the free FPs a threshold reaches.)
  std::sort(free_fp_dets.begin(), free_fp_dets.end(),
            [&](int32_t a, int32_t b) { return f.det_score[a] > f.det_score[b]; });
  std::vector<int64_t>& bin_free_fp = scratch.bin_free_fp;
  bin_free_fp.assign(n_s, 0);
  FrameAssociation& a = scratch.association;
  const size_t nd = static_cast<size_t>(f.num_dets);

  // The counts change only where a detection enters (its score >= the threshold), so the
  // thresholds go by runs over which nothing enters: the greedy runs once per run, and every
  // threshold of the run gets the same counts.
  const size_t n_inter = interacting_scores.size(), n_free = free_fp_scores.size();
  size_t k_inter = 0, k_free = 0;
  KittiCounts cached;
  for (size_t t = 0; t < n_t;) {
    const double threshold = thresholds[t];
    const size_t inter_before = k_inter, free_before = k_free;
    while (k_inter < n_inter && interacting_scores[k_inter] >= threshold) ++k_inter;
    while (k_free < n_free && free_fp_scores[k_free] >= threshold) ++k_free;
    if (t == 0 || k_inter != inter_before) {
      cached = KittiCounts{};
      if (k_inter == 0) {
        cached.fn = n_valid;  // (the bins' tallies: still those of no detection)
      } else {
        FrameAssociation* assoc = nullptr;
        if (n_s > 0) {
          a.label_outcome.assign(f.num_labels, Outcome::kIgnored);
          a.label_det.assign(f.num_labels, -1);
          a.det_outcome.assign(f.num_dets, Outcome::kNone);
          a.det_label.assign(f.num_dets, -1);
          assoc = &a;
          bin_tallies.assign(n_s, Tally{});
        }
        const Pass2Result r = RunPass2(f, states, threshold, &scratch.assigned, assoc);
        const uint8_t* const assigned = scratch.assigned.data();
        cached.tp = r.tp;
        cached.fn = r.fn;
        cached.similarity = r.similarity;
        if (n_s > 0) TallyLabels(frame, a, *bins->masks, n_s, bin_tallies.data());
        for (int j = 0; j < f.num_dets; ++j) {
          if (interacting[j] && states[j] == 0 && !assigned[j] && f.det_score[j] >= threshold &&
              !f.det_dontcare[j]) {
            ++cached.fp;
            for (size_t s = 0; s < n_s; ++s) bin_tallies[s].fp += bins->masks->det[s * nd + j];
          }
        }
      }
    }
    for (size_t k = free_before; k < k_free && n_s > 0; ++k) {
      const size_t j = static_cast<size_t>(free_fp_dets[k]);
      for (size_t s = 0; s < n_s; ++s) bin_free_fp[s] += bins->masks->det[s * nd + j];
    }
    // The run ends at the first threshold after t at which the next detection of either list
    // enters (score >= threshold). The thresholds descend (and hold no NaN: they are TP scores), so
    // the thresholds a score does not reach are a prefix: a binary search finds the end.
    size_t end = n_t;
    auto first_entered = [&](double score) {
      return static_cast<size_t>(
          std::partition_point(thresholds.begin() + static_cast<ptrdiff_t>(t) + 1,
                               thresholds.begin() + static_cast<ptrdiff_t>(n_t),
                               [score](double threshold) { return !(score >= threshold); }) -
          thresholds.begin());
    };
    if (k_inter < n_inter) end = std::min(end, first_entered(interacting_scores[k_inter]));
    if (k_free < n_free) end = std::min(end, first_entered(free_fp_scores[k_free]));
    counts->AddRun(t, end, cached.tp, cached.fp + static_cast<int64_t>(k_free), cached.fn,
                   cached.similarity);
    for (size_t s = 0; s < n_s; ++s) {
      const Tally& tally = bin_tallies[s];
      bins->counts[s].AddRun(t, end, tally.tp, tally.fp + bin_free_fp[s], tally.fn,
                             tally.similarity);
    }
    t = end;
  }
}

}  // namespace

std::vector<KittiCounts> KittiAddFrameCounts(const ClassFrame& f, Difficulty difficulty,
                                             const std::vector<double>& thresholds,
                                             std::vector<KittiCounts> counts) {
  if (counts.size() < thresholds.size()) counts.resize(thresholds.size());
  PassTwoCounts frame_counts(thresholds.size());
  AddFrameCounts(f, difficulty, thresholds, &frame_counts);
  frame_counts.AddTo(&counts);
  return counts;
}

FrameAssociation KittiAssociate(const ClassFrame& frame, Difficulty difficulty, double threshold,
                                FrameAssociation reuse) {
  ThreadScratch& scratch = Scratch();
  const DetStateView states = DetStates(frame, difficulty, &scratch.states);
  const FrameView f(frame, difficulty);
  FrameAssociation a = std::move(reuse);
  a.label_outcome.assign(f.num_labels, Outcome::kIgnored);
  a.label_det.assign(f.num_labels, -1);
  a.det_outcome.assign(f.num_dets, Outcome::kNone);
  a.det_label.assign(f.num_dets, -1);
  RunPass2(f, states, threshold, &scratch.assigned, &a);
  const uint8_t* const assigned = scratch.assigned.data();
  Outcome* const det_outcome = a.det_outcome.data();
  for (int j = 0; j < f.num_dets; ++j) {
    if (det_outcome[j] == Outcome::kTp) continue;
    if (states[j] == -1 || f.det_score[j] < threshold) continue;  // kNone
    if (states[j] == 1 || assigned[j]) {
      det_outcome[j] = Outcome::kIgnored;
    } else if (f.det_dontcare[j]) {
      det_outcome[j] = Outcome::kDontCare;
    } else {
      det_outcome[j] = Outcome::kFp;
    }
  }
  return a;
}

double KittiApR11(const std::array<double, kKittiSamplePoints>& curve) {
  double sum = 0.0;
  for (int i = 0; i < kKittiSamplePoints; i += 4) sum += curve[i];
  return sum / 11.0 * 100.0;
}

double KittiApR40(const std::array<double, kKittiSamplePoints>& curve) {
  double sum = 0.0;
  for (int i = 1; i < kKittiSamplePoints; ++i) sum += curve[i];
  return sum / 40.0 * 100.0;
}

struct KittiPasses::Blocks {
  // Pass 1, by difficulty then block: the TP scores in frame order, the valid labels.
  std::vector<std::vector<std::vector<double>>> scores;
  std::vector<std::vector<int64_t>> groundtruth;
  // Pass 2, by difficulty then block; the bins', by difficulty, block, then bin.
  std::vector<std::vector<PassTwoCounts>> counts;
  std::vector<std::vector<std::vector<PassTwoCounts>>> bin_counts;
};

KittiPasses::KittiPasses(size_t num_frames, std::vector<Difficulty> difficulties, EvalCompat compat)
    : difficulties_(std::move(difficulties)),
      compat_(compat),
      num_blocks_((num_frames + kBlock - 1) / kBlock),
      results_(difficulties_.size()),
      blocks_(std::make_unique<Blocks>()) {
  blocks_->scores.assign(difficulties_.size(), std::vector<std::vector<double>>(num_blocks_));
  blocks_->groundtruth.assign(difficulties_.size(), std::vector<int64_t>(num_blocks_, 0));
}

KittiPasses::~KittiPasses() = default;

void KittiPasses::CollectFrame(size_t frame_index, const ClassFrame& frame) {
  const size_t b = frame_index / kBlock;
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    KittiTpScores tp =
        KittiCollectTpScores(frame, difficulties_[d], std::move(blocks_->scores[d][b]));
    blocks_->scores[d][b] = std::move(tp.scores);
    blocks_->groundtruth[d][b] += tp.num_groundtruth;
  }
}

void KittiPasses::ChooseThresholds() {
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    KittiClassResult& result = results_[d];
    std::vector<double> v;
    for (size_t b = 0; b < num_blocks_; ++b) {
      result.num_groundtruth += blocks_->groundtruth[d][b];
      v.insert(v.end(), blocks_->scores[d][b].begin(), blocks_->scores[d][b].end());
    }
    result.thresholds = KittiThresholds(std::move(v), static_cast<double>(result.num_groundtruth));
    // The devkit writes precision[i] for every threshold into 41 slots; more than 41 thresholds
    // cannot happen (see KittiThresholds), but never write past the array.
    if (result.thresholds.size() > kKittiSamplePoints) result.thresholds.resize(kKittiSamplePoints);
    blocks_->counts.emplace_back(num_blocks_, PassTwoCounts(result.thresholds.size()));
  }
}

void KittiPasses::UseThresholds(const std::vector<std::vector<double>>& thresholds) {
  STEREODET_CHECK(thresholds.size() == difficulties_.size())
      << "KittiPasses::UseThresholds: " << thresholds.size() << " lists for "
      << difficulties_.size() << " difficulties";
  blocks_->counts.clear();
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    KittiClassResult& result = results_[d];
    result.thresholds = thresholds[d];
    if (result.thresholds.size() > kKittiSamplePoints) result.thresholds.resize(kKittiSamplePoints);
    blocks_->counts.emplace_back(num_blocks_, PassTwoCounts(result.thresholds.size()));
  }
}

void KittiPasses::SetBins(const std::vector<BinMasks>* masks, size_t num_bins) {
  bin_masks_ = masks;
  num_bins_ = masks != nullptr ? num_bins : 0;
  blocks_->bin_counts.clear();
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    blocks_->bin_counts.emplace_back(
        num_blocks_,
        std::vector<PassTwoCounts>(num_bins_, PassTwoCounts(results_[d].thresholds.size())));
  }
}

void KittiPasses::CountFrame(size_t frame_index, const ClassFrame& frame) {
  const size_t b = frame_index / kBlock;
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    if (num_bins_ == 0) {
      AddFrameCounts(frame, difficulties_[d], results_[d].thresholds, &blocks_->counts[d][b]);
      continue;
    }
    const FrameBins bins{&(*bin_masks_)[frame_index], num_bins_, blocks_->bin_counts[d][b].data()};
    AddFrameCounts(frame, difficulties_[d], results_[d].thresholds, &blocks_->counts[d][b], &bins);
  }
}

void KittiSlots(const std::vector<KittiCounts>& counts, EvalCompat compat, bool empty_slots_zero,
                std::array<double, kKittiSamplePoints>* precision,
                std::array<double, kKittiSamplePoints>* aos) {
  const size_t n_t = std::min<size_t>(counts.size(), kKittiSamplePoints);
  precision->fill(0.0);
  aos->fill(0.0);
  for (size_t i = 0; i < n_t; ++i) {
    const KittiCounts& c = counts[i];
    if (empty_slots_zero && c.tp + c.fp == 0) continue;
    (*precision)[i] = static_cast<double>(c.tp) / static_cast<double>(c.tp + c.fp);
    (*aos)[i] = c.similarity / static_cast<double>(c.tp + c.fp);
  }
  if (compat == EvalCompat::kOpenPcdet) {
    *precision = OpenPcdetEnvelope(*precision);
    *aos = OpenPcdetEnvelope(*aos);
  } else {
    for (size_t i = 0; i < n_t; ++i) {
      (*precision)[i] = *std::max_element(precision->begin() + i, precision->end());
      (*aos)[i] = *std::max_element(aos->begin() + i, aos->end());
    }
  }
}

std::vector<KittiClassResult> KittiPasses::Finish() {
  for (size_t d = 0; d < difficulties_.size(); ++d) {
    KittiClassResult& result = results_[d];
    const size_t n_t = result.thresholds.size();
    result.counts.assign(n_t, KittiCounts{});
    for (size_t b = 0; b < num_blocks_; ++b) blocks_->counts[d][b].AddTo(&result.counts);

    for (size_t i = 0; i < n_t; ++i) {
      const KittiCounts& c = result.counts[i];
      result.recall[i] = static_cast<double>(c.tp) / static_cast<double>(c.tp + c.fn);
    }
    // Precision, AOS, envelope: the devkit's arithmetic, NaN (0 / 0) included.
    KittiSlots(result.counts, compat_, /*empty_slots_zero=*/false, &result.precision, &result.aos);
    result.ap_r11 = KittiApR11(result.precision);
    result.ap_r40 = KittiApR40(result.precision);
    result.aos_r11 = KittiApR11(result.aos);
    result.aos_r40 = KittiApR40(result.aos);
    result.bin_counts.assign(num_bins_, std::vector<KittiCounts>(n_t));
    for (size_t s = 0; s < num_bins_; ++s) {
      for (size_t b = 0; b < num_blocks_; ++b) {
        blocks_->bin_counts[d][b][s].AddTo(&result.bin_counts[s]);
      }
    }
  }
  return std::move(results_);
}

std::vector<KittiClassResult> EvaluateKittiClass(const std::vector<ClassFrame>& frames,
                                                 const std::vector<Difficulty>& difficulties,
                                                 int num_threads, EvalCompat compat) {
  KittiPasses passes(frames.size(), difficulties, compat);
  const size_t num_blocks = (frames.size() + KittiPasses::kBlock - 1) / KittiPasses::kBlock;
  auto for_each_frame = [&](auto fn) {
    ParallelFor(
        num_blocks,
        [&](size_t b) {
          for (size_t i = b * KittiPasses::kBlock;
               i < std::min(frames.size(), (b + 1) * KittiPasses::kBlock); ++i) {
            fn(i);
          }
        },
        num_threads);
  };
  for_each_frame([&](size_t i) { passes.CollectFrame(i, frames[i]); });
  passes.ChooseThresholds();
  for_each_frame([&](size_t i) { passes.CountFrame(i, frames[i]); });
  return passes.Finish();
}

KittiClassResult EvaluateKittiClass(const std::vector<ClassFrame>& frames, Difficulty difficulty,
                                    int num_threads, EvalCompat compat) {
  return EvaluateKittiClass(frames, std::vector<Difficulty>{difficulty}, num_threads, compat)[0];
}

}  // namespace stereodet
