// Internal to the eval module (used by Evaluate, its tests and benchmarks; not by other modules).
//
// KITTI's official devkit (devkit_object, cpp/evaluate_object.cpp), reproduced exactly, quirks
// kept: see docs/metrics.md, section "KITTI-compatible mode", for each quirk and the test that
// shows it.
//
// Per class, overlap kind and difficulty the devkit
//  1. matches every frame greedily, label by label in file order, each label taking the unassigned
//     detection with overlap > threshold and the HIGHEST SCORE; the scores of the true positives
//     are collected over all frames (pass 1);
//  2. picks at most 41 score thresholds from those TP scores (getThresholds);
//  3. at each threshold, matches every frame again with detections of lower score left out, each
//     label now taking the detection with the LARGEST OVERLAP (pass 2), and counts TP, FP (minus
//     detections inside DontCare regions) and FN, and sums the orientation similarity of the TPs;
//  4. precision[i] = TP / (TP + FP) at threshold i (41 slots, zero beyond the thresholds), replaced
//  by
//     its maximum over i..40 (the envelope); the same for AOS;
//  5. AP_R11 = sum of precision[0, 4, ..., 40] / 11, AP_R40 = sum of precision[1..40] / 40, in %.
#ifndef STEREODET_EVAL_KITTI_MATCHER_INTERNAL_H_
#define STEREODET_EVAL_KITTI_MATCHER_INTERNAL_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/selection_mask_internal.h"

namespace stereodet {

inline constexpr int kKittiSamplePoints = 41;  // N_SAMPLE_PTS

// getThresholds: sorts `tp_scores` descending and walks them, keeping a score when its recall
// (i+1)/n_groundtruth is at least as close to the next recall step (0, 1/40, 2/40, ..., accumulated
// in floating point as the devkit does) as the following score's; the last score is always kept.
// Returns the kept scores, descending (at most 41 of them).
std::vector<double> KittiThresholds(std::vector<double> tp_scores, double n_groundtruth);

// Pass 1 on one frame: the scores of its true positives, appended to `append_to` (frames' scores
// collect in one list), and its number of valid labels (the recall denominator's share).
struct KittiTpScores {
  std::vector<double> scores;
  int num_groundtruth = 0;
};
KittiTpScores KittiCollectTpScores(const ClassFrame& frame, Difficulty difficulty,
                                   std::vector<double> append_to = {});

struct KittiCounts {
  int64_t tp = 0, fp = 0, fn = 0;
  double similarity = 0.0;  // sum of (1 + cos(alpha_label - alpha_det)) / 2 over the TPs
};

// Pass 2's counts of many frames at every threshold (KittiPasses', and a breakdown bin's in
// Evaluate). A frame's counts are constant over runs of
// thresholds, so its integer counts are recorded as changes at the ends of its runs (summed up in
// AddTo, exact in any order), while each threshold's similarity sum gets the frame's value added
// at each threshold of a run, frame after frame: a floating-point sum depends on its order, and
// this is the order of adding every frame's counts threshold by threshold. Zero similarities are
// not added (x + 0 is x for every sum here, none of which is -0).
class PassTwoCounts {
 public:
  explicit PassTwoCounts(size_t num_thresholds)
      : tp_(num_thresholds + 1, 0),
        fp_(num_thresholds + 1, 0),
        fn_(num_thresholds + 1, 0),
        similarity_(num_thresholds, 0.0) {}

  size_t num_thresholds() const { return similarity_.size(); }

  // Adds the counts to the thresholds [begin, end).
  void AddRun(size_t begin, size_t end, int64_t tp, int64_t fp, int64_t fn, double similarity) {
    tp_[begin] += tp;
    tp_[end] -= tp;
    fp_[begin] += fp;
    fp_[end] -= fp;
    fn_[begin] += fn;
    fn_[end] -= fn;
    if (similarity != 0.0) {
      for (size_t t = begin; t < end; ++t) similarity_[t] += similarity;
    }
  }

  // Adds the sums to counts[t], t < num_thresholds().
  void AddTo(std::vector<KittiCounts>* counts) const {
    int64_t tp = 0, fp = 0, fn = 0;
    for (size_t t = 0; t < similarity_.size(); ++t) {
      tp += tp_[t];
      fp += fp_[t];
      fn += fn_[t];
      KittiCounts& c = (*counts)[t];
      c.tp += tp;
      c.fp += fp;
      c.fn += fn;
      c.similarity += similarity_[t];
    }
  }

 private:
  std::vector<int64_t> tp_, fp_, fn_;
  std::vector<double> similarity_;
};

// Pass 2 on one frame at every threshold of `thresholds` (descending): `counts` (resized to one
// per threshold if shorter) with each threshold's counts added to counts[t]. Equivalent to the
// devkit's computeStatistics(compute_fp = true) per threshold, but the greedy is rerun only when
// the set of overlapping detections above the threshold changes.
std::vector<KittiCounts> KittiAddFrameCounts(const ClassFrame& frame, Difficulty difficulty,
                                             const std::vector<double>& thresholds,
                                             std::vector<KittiCounts> counts = {});

// Pass 2 on one frame at one threshold, returning what every label and detection counts as.
// `reuse` lends its memory to the result (its contents are discarded).
FrameAssociation KittiAssociate(const ClassFrame& frame, Difficulty difficulty, double threshold,
                                FrameAssociation reuse = {});

struct KittiClassResult {
  int64_t num_groundtruth = 0;                         // n_gt: valid labels over all frames
  std::vector<double> thresholds;                      // descending, <= 41
  std::vector<KittiCounts> counts;                     // per threshold
  std::array<double, kKittiSamplePoints> precision{};  // after the envelope, as the devkit saves it
  std::array<double, kKittiSamplePoints> aos{};        // idem (valid only if AOS was computed)
  std::array<double, kKittiSamplePoints> recall{};     // TP / (TP + FN) per threshold, 0 beyond
  double ap_r11 = 0.0, ap_r40 = 0.0;                   // percent
  double aos_r11 = 0.0, aos_r40 = 0.0;                 // percent (valid only if AOS was computed)
  // With KittiPasses::SetBins: each breakdown bin's counts per threshold (of the same pass 2
  // associations, counted under the bin's masks as TallyBins counts them).
  std::vector<std::vector<KittiCounts>> bin_counts;
};

// The devkit's arithmetic on pass 2's counts (at most 41 thresholds): precision TP / (TP + FP) and
// AOS similarity / (TP + FP) per threshold in 41 slots (0 beyond the thresholds; 0 / 0 is NaN as
// in the devkit, or 0 with `empty_slots_zero`), each replaced by its envelope (the maximum over
// the slots from it on; numpy's with EvalCompat::kOpenPcdet, see OpenPcdetEnvelope).
void KittiSlots(const std::vector<KittiCounts>& counts, EvalCompat compat, bool empty_slots_zero,
                std::array<double, kKittiSamplePoints>* precision,
                std::array<double, kKittiSamplePoints>* aos);

// Runs passes 1-5 over all frames (parallel over frames). With EvalCompat::kOpenPcdet the envelope
// is numpy's (OpenPcdetEnvelope: a NaN slot makes every slot before it NaN); the rest is the same.
KittiClassResult EvaluateKittiClass(const std::vector<ClassFrame>& frames, Difficulty difficulty,
                                    int num_threads, EvalCompat compat = EvalCompat::kDevkit);
// The same for several difficulties at once (each frame's passes for all of them together): one
// result per difficulty, in their order, each equal to EvaluateKittiClass's for that difficulty.
std::vector<KittiClassResult> EvaluateKittiClass(const std::vector<ClassFrame>& frames,
                                                 const std::vector<Difficulty>& difficulties,
                                                 int num_threads,
                                                 EvalCompat compat = EvalCompat::kDevkit);

// EvaluateKittiClass in steps, for a caller that does other work on each frame in the same passes
// (each frame's data then comes from memory once): CollectFrame(i, frames[i]) for every frame
// (pass 1), ChooseThresholds(), CountFrame(i, frames[i]) for every frame (pass 2), Finish(). The
// frames of one block (i / kBlock) go in order on one thread; blocks in any order, on any threads
// (each writes only its own sums, added up in block order). Results as EvaluateKittiClass's.
class KittiPasses {
 public:
  static constexpr size_t kBlock = 64;

  KittiPasses(size_t num_frames, std::vector<Difficulty> difficulties,
              EvalCompat compat = EvalCompat::kDevkit);
  ~KittiPasses();
  KittiPasses(const KittiPasses&) = delete;
  KittiPasses& operator=(const KittiPasses&) = delete;

  void CollectFrame(size_t frame_index, const ClassFrame& frame);
  void ChooseThresholds();
  // Instead of CollectFrame and ChooseThresholds: pass 2 at these thresholds, one list per
  // difficulty (descending; at most 41 used), e.g. an unfiltered evaluation's for a stable filter.
  void UseThresholds(const std::vector<std::vector<double>>& thresholds);
  // Optional, after ChooseThresholds and before any CountFrame: count breakdown bins too, frame
  // i's masks (of `num_bins` bins) being (*masks)[i] (outliving the passes); their counts in each
  // result's bin_counts.
  void SetBins(const std::vector<BinMasks>* masks, size_t num_bins);
  void CountFrame(size_t frame_index, const ClassFrame& frame);
  // One result per difficulty, in the constructor's order.
  std::vector<KittiClassResult> Finish();

 private:
  struct Blocks;
  std::vector<Difficulty> difficulties_;
  EvalCompat compat_;
  size_t num_blocks_;
  const std::vector<BinMasks>* bin_masks_ = nullptr;
  size_t num_bins_ = 0;
  std::vector<KittiClassResult> results_;
  std::unique_ptr<Blocks> blocks_;
};

// The devkit's summaries of a 41-slot curve, in percent: sum of [0,4,...,40] / 11 and [1..40] / 40.
double KittiApR11(const std::array<double, kKittiSamplePoints>& curve);
double KittiApR40(const std::array<double, kKittiSamplePoints>& curve);

}  // namespace stereodet

#endif  // STEREODET_EVAL_KITTI_MATCHER_INTERNAL_H_
