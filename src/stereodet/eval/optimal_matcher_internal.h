// Internal to the eval module (used by Evaluate, its tests and benchmarks; not by other modules).
//
// The paper's optimal matcher: per frame and class, the association of detections to labels with
// overlap >= tau that has the most true positives, then the fewest false positives and false
// negatives, then the largest total overlap (LET kinds: LET-IoU x affinity, ClassFrame::EdgeWeight,
// the weight Waymo's matcher maximises alone). Exact (integer lexicographic weights, no (IoU +
// n)/2n^2 scaling), each connected component of the overlap graph solved on its own.
//
// Who takes part, per difficulty (KITTI's meaning, see docs/metrics.md "Optimal matching"):
//  - valid labels: the class, meeting the difficulty; ignored labels: neighbour classes (Van for
//    Car, Person_sitting for Pedestrian) and labels of the class that miss the difficulty;
//  - valid detections: the class, 2D height >= the difficulty's minimum; ignored detections: the
//    class, lower than that. Detections of other classes take no part (unlike the devkit, where a
//    low detection of any class may absorb a label).
//  - TP: a pair (valid label, valid detection) with overlap >= tau, in a maximum matching.
//  - a valid detection left unmatched is not a FP if it overlaps (>= tau) an ignored label, or a
//    DontCare region by > tau (intersection over its own area, as KITTI); these excuse any number.
//  - a valid label left unmatched is not a FN if an ignored detection above the threshold overlaps
//    it (>= tau).
//  Among the maximum matchings the one excusing the most is chosen (it exists: Mendelsohn-Dulmage),
//  so TP, FP and FN at a threshold are those of one association.
#ifndef STEREODET_EVAL_OPTIMAL_MATCHER_INTERNAL_H_
#define STEREODET_EVAL_OPTIMAL_MATCHER_INTERNAL_H_

#include <cstdint>
#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/curves.h"
#include "stereodet/eval/frame_data_internal.h"

namespace stereodet {

// Valid labels of the frame at `difficulty` (the recall denominator when nothing is excused).
int CountValidLabels(const ClassFrame& frame, Difficulty difficulty);

// Appends the frame's curve events: TP(t), FP(t), FN(t) exact at every threshold t, computed in one
// pass over the detections in descending score with one augmenting-path search per detection in
// each of three incremental matchings (TP: all valid detections; FP: the valid detections no
// ignored label or DontCare excuses; FN: the labels no ignored detection above t excuses). Returns
// `append_to` with them appended.
std::vector<CurveEvent> OptimalFrameEvents(const ClassFrame& frame, Difficulty difficulty,
                                           std::vector<CurveEvent> append_to = {});

// The association at `threshold` (detections with score >= threshold): maximum TPs, then most
// excused detections and labels, then largest total overlap; Hungarian per connected component.
// `reuse` lends its memory to the result (its contents are discarded).
FrameAssociation OptimalAssociate(const ClassFrame& frame, Difficulty difficulty, double threshold,
                                  FrameAssociation reuse = {});

// OptimalAssociate of one frame at many thresholds, its overlap graph built once (in this thread's
// memory, where every optimal-matcher call builds its graph): construct, then At(threshold) as
// often as needed. Precondition: At runs on the constructing thread with no other optimal-matcher
// call on that thread in between (checked: an exception, not a wrong association); `frame` outlives
// the object.
class OptimalAssociator {
 public:
  OptimalAssociator(const ClassFrame& frame, Difficulty difficulty);
  FrameAssociation At(double threshold, FrameAssociation reuse = {}) const;
  // OptimalFrameEvents(frame, difficulty) appended to *events, on the same graph.
  void AppendFrameEvents(std::vector<CurveEvent>* events) const;
  const ClassFrame& frame() const { return frame_; }

 private:
  // The thread's graph is still the one this object built (else an exception).
  void CheckGraph() const;

  const ClassFrame& frame_;
  uint64_t graph_generation_;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_OPTIMAL_MATCHER_INTERNAL_H_
