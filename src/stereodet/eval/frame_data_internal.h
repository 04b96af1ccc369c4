// Internal to the eval module: the per-frame, per-class, per-overlap-kind data every matcher works
// on (computed once, reused for all difficulties and all score thresholds), and the overlaps in
// the devkit's arithmetic it is made of.
#ifndef STEREODET_EVAL_FRAME_DATA_INTERNAL_H_
#define STEREODET_EVAL_FRAME_DATA_INTERNAL_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/kitti/object.h"

namespace stereodet {

// Half-width of the band around a class threshold (and around another overlap of the same label,
// see PrepareClassFrame) in which KITTI mode recomputes a BEV / 3D overlap in the devkit's
// arithmetic. The devkit's boost::geometry (1.74) snaps coordinates to an integer grid of ~1e7
// steps across the two boxes, so its overlaps differ from KittiOverlap's exact ones by up to ~1e-6
// for KITTI-like boxes and ~1e-5 for boxes 1-10 cm wide (measured on 10^6 pairs); 1e-4 covers
// both.
inline constexpr double kDevkitTieBand = 1e-4;

// The overlap KITTI mode decides `> tau` with and stores (ClassFrame::edge_overlap): KittiOverlap,
// except in BEV and 3D, where the devkit's own value (DevkitBoxOverlap, devkit_overlap_internal.h)
// replaces a positive KittiOverlap
//  - within kDevkitTieBand of `tau`: an overlap mathematically equal to tau (a box shifted by a
//    third of its length, or in y by the right amount) then falls on the devkit's side of it;
//  - of footprints with parallel edges (rotations equal modulo 90 degrees, to 1e-4 rad) that are
//    not identical: boost 1.74 loses the intersection of some of them (measured: ~2% of the pairs
//    where one footprint lies inside the other between common end lines, e.g. a detection that
//    differs from its label only in width), and the devkit then sees overlap 0.
// Where the devkit has no answer (it crashes) KittiOverlap's value is kept. Requires: tau in
// (0, 1].
double KittiOverlapAtThreshold(OverlapKind kind, const Object& detection, const Object& label,
                               double tau);
// The same for the DontCare test (KittiDontCareOverlap; the devkit's criterion 0).
double KittiDontCareOverlapAtThreshold(OverlapKind kind, const Object& detection,
                                       const Object& dontcare, double tau);

// Which overlap values PrepareClassFrame stores.
enum class OverlapArithmetic {
  kExact,   // KittiOverlap / KittiDontCareOverlap everywhere (optimal and VOC matchers)
  kDevkit,  // KITTI mode: the devkit's own values where they may decide differently (see below)
};

// The labels that concern one class (the class and its neighbours, file order), the detections that
// may take part (the class, plus any detection lower than 40 px, which KITTI's devkit treats as an
// "ignored" detection whatever its class), and the overlaps >= the class threshold between them.
struct ClassFrame {
  // Labels: the class or a neighbour class, in file order.
  std::vector<int32_t> label_object;      // index into EvalFrame::labels
  std::vector<uint8_t> label_neighbour;   // 1 for a neighbour class (always ignored)
  std::vector<uint8_t> label_difficulty;  // bit d set if the label meets difficulty d
  std::vector<double> label_alpha;
  // Detections: the class, or 2D height < 40 px (any class), in file order.
  std::vector<int32_t> det_object;    // index into EvalFrame::detections
  std::vector<uint8_t> det_is_class;  // 1 if of the evaluated class
  std::vector<double> det_height;     // |bottom - top|, px
  std::vector<double> det_score;
  std::vector<double> det_alpha;
  std::vector<uint8_t> det_dontcare;  // overlaps a DontCare region by > the threshold (criterion 0)
  // The devkit's ignored_det of each detection for each difficulty, det_state[j * kNumDifficulties
  // + d]: 1 if lower than d's minimum height (std::trunc(det_height) < min), else 0 for the
  // evaluated class and -1 for another. Derived from det_height and det_is_class by
  // ClassFrameBuilder (once per frame, class and overlap kind, instead of once per KITTI pass and
  // difficulty); a ClassFrame put together by hand may leave it empty, and the KITTI matcher then
  // derives it itself.
  std::vector<int8_t> det_state;
  // Overlaps >= min_overlap, by label (CSR): label i's edges are [edge_begin[i], edge_begin[i+1]),
  // in ascending detection order.
  std::vector<int32_t> edge_begin;
  std::vector<int32_t> edge_det;
  std::vector<double> edge_overlap;
  // LET kinds only (empty otherwise): each edge's longitudinal affinity (let.h), in (0, 1]. An edge
  // needs LET-IoU >= min_overlap and an affinity above 0.
  std::vector<double> edge_affinity;
  double min_overlap = 0.5;
  // Made by PrepareClassFrame with OverlapArithmetic::kDevkit (see KittiRecordedOverlap).
  bool devkit_overlaps = false;
  // PrepareClassFrame's memory for the next overlap kind of the same frame and class: the footprint
  // intersection of label i and detection j, pair_footprint[i * num_dets() + j], once a BEV or 3D
  // ClassFrame of this selection was made (empty otherwise).
  std::vector<double> pair_footprint;

  // What every matcher prefers among a label's (or a detection's) candidate edges: the overlap, or
  // for the LET kinds LET-IoU x affinity, the weight Waymo's matcher maximises.
  double EdgeWeight(int e) const {
    return edge_affinity.empty() ? edge_overlap[e] : edge_overlap[e] * edge_affinity[e];
  }
  // A true positive's weight in the TP-weighted AP (edge e pairs label i and detection j): the
  // orientation similarity (1 + cos(alpha_d - alpha_l)) / 2 (AOS), or for the LET kinds the
  // longitudinal affinity (LET-APL).
  double TpWeight(int i, int j, int e) const {
    return edge_affinity.empty() ? (1.0 + std::cos(det_alpha[j] - label_alpha[i])) / 2.0
                                 : edge_affinity[e];
  }

  // The detections' distinct scores, descending: where the set of detections above a threshold
  // (and so any association at it) can change.
  std::vector<double> DistinctScores() const {
    std::vector<double> scores = det_score;
    std::sort(scores.begin(), scores.end(), std::greater<double>());
    scores.erase(std::unique(scores.begin(), scores.end()), scores.end());
    return scores;
  }

  int num_labels() const { return static_cast<int>(label_object.size()); }
  int num_dets() const { return static_cast<int>(det_object.size()); }
  // Empties every list, keeping its memory (see PrepareClassFrame's `reuse`).
  void Clear();
  bool LabelValid(int i, Difficulty d) const {
    return !label_neighbour[i] && (label_difficulty[i] >> static_cast<int>(d) & 1);
  }
  // The edge (an index into edge_det / edge_overlap) of label i with detection j, or -1 when
  // their overlap is below min_overlap (no edge).
  int FindEdge(int i, int j) const {
    for (int e = edge_begin[i]; e < edge_begin[i + 1]; ++e) {
      if (edge_det[e] == j) return e;
    }
    return -1;
  }
};

// PrepareClassFrame's first two steps, shared with PrepareClassFrameOpenPcdet: which labels and
// detections take part, appended to a ClassFrame that Take() then hands over (with
// ClassFrame::edge_* and min_overlap left to the caller).
class ClassFrameBuilder {
 public:
  // `reuse` lends its memory (its contents are discarded).
  explicit ClassFrameBuilder(ClassFrame reuse = {});
  // Builds in `*target` (its contents are discarded), which must outlive the builder; Take() then
  // moves it out, and without Take() the result stays there.
  explicit ClassFrameBuilder(ClassFrame* target);
  ClassFrameBuilder(const ClassFrameBuilder&) = delete;
  ClassFrameBuilder& operator=(const ClassFrameBuilder&) = delete;

  // The labels of `spec`'s class and of its neighbour classes (file order; neighbours always
  // ignored; difficulty bits by the official devkit's cleanData: ignored if occluded > max,
  // truncated > max or 2D height <= min). Also finds the frame's DontCare regions (dontcares()),
  // named "DontCare" exactly when `exact_dontcare_name` (OpenPCDet's rule), in any case otherwise
  // (the devkit's).
  void AddLabels(const EvalFrame& frame, const ClassSpec& spec, bool exact_dontcare_name);
  // In file order, the detections of `spec`'s class and those of any class lower than 40 px (the
  // devkit's "ignored" detections), with the DontCare flag `in_dontcare(detection)` for those of
  // the class. Throws std::invalid_argument naming the frame if a detection has no score.
  void AddDetections(const EvalFrame& frame, const ClassSpec& spec,
                     const std::function<bool(const Object&)>& in_dontcare);

  const ClassFrame& frame() const { return *cf_; }
  const std::vector<const Object*>& dontcares() const { return dontcares_; }  // into frame.labels
  ClassFrame Take() { return std::move(*cf_); }

 private:
  ClassFrame own_;
  ClassFrame* cf_;  // &own_ or the target
  std::vector<const Object*> dontcares_;
};

// Builds the ClassFrame of `frame` for `spec` and `kind`. With OverlapArithmetic::kDevkit, overlaps
// and the DontCare test are KittiOverlapAtThreshold's and KittiDontCareOverlapAtThreshold's at the
// class threshold, and in BEV and 3D two overlaps of one label (both >= the threshold) that lie
// within kDevkitTieBand of each other are both the devkit's values too: KITTI's pass 2 takes the
// larger, and the devkit may order (or tie) two mathematically equal overlaps otherwise than
// KittiOverlap does, e.g. two detections shifted by the same distance either side of a label. All
// of this is rare; every other overlap is KittiOverlap's. `reuse` lends its memory to the result
// (its contents are discarded): an evaluation prepares every frame once per class and overlap kind,
// and reusing the previous ClassFrame's lists saves allocating them afresh each time. With
// `reuse_selection`, `reuse` must be a result of PrepareClassFrame for this very frame and `spec`
// (any overlap kind, any arithmetic): its labels and detections are kept instead of being selected
// again, and BEV and 3D share each pair's footprint intersection (ClassFrame::pair_footprint); the
// result is the same, bit for bit. The LET kinds (`let` their tolerance) store LET-IoU in
// edge_overlap and the affinity in edge_affinity, always in exact arithmetic (the devkit has no
// LET), and neither read nor write pair_footprint. Requires: every detection has a score.
ClassFrame PrepareClassFrame(const EvalFrame& frame, const ClassSpec& spec, OverlapKind kind,
                             OverlapArithmetic arithmetic = OverlapArithmetic::kDevkit,
                             ClassFrame reuse = {}, bool reuse_selection = false,
                             const LetOptions& let = LetOptions());
// The same in place: `*cf` is the `reuse` above and becomes the result (no ClassFrame moved).
void PrepareClassFrameInPlace(const EvalFrame& frame, const ClassSpec& spec, OverlapKind kind,
                              OverlapArithmetic arithmetic, bool reuse_selection, ClassFrame* cf,
                              const LetOptions& let = LetOptions());

// The overlap of label `label_index`'s edge `edge` (an index into cf.edge_det) that records
// (matches.csv) report: cf.edge_overlap[edge], except in a ClassFrame of PrepareClassFrame with
// OverlapArithmetic::kDevkit, BEV or 3D, where it is the devkit's own value wherever the devkit may
// be asked: near the threshold, between close candidates of the label, and for EVERY parallel,
// non-identical pair. PrepareClassFrame itself keeps KittiOverlap's value for parallel footprints
// whose edge lines are all apart: there the two stay within 3e-6 of each other, far from the
// threshold and from the label's other candidates, so every decision is the same (the set of
// edges included), but the value differs in the last digits, and records print the devkit's.
double KittiRecordedOverlap(OverlapKind kind, const EvalFrame& frame, const ClassFrame& cf,
                            int label_index, int edge);

}  // namespace stereodet

#endif  // STEREODET_EVAL_FRAME_DATA_INTERNAL_H_
