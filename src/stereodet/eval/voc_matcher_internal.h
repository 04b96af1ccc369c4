// Internal to the eval module (used by Evaluate, its tests and benchmarks; not by other modules).
//
// PASCAL VOC matching: the detections of a frame in descending score (file order among ties), each
// assigned to the label it overlaps most (among all labels of the class and its neighbours); a TP
// if that overlap is >= tau and the label is valid and not yet taken, nothing if the label is
// ignored
// ("difficult"), else a FP. KITTI's other rules are kept so the tables compare: detections lower
// than the difficulty's minimum height are ignored (one that hits a free valid label excuses it, as
// in KITTI), and a FP inside a DontCare region (> tau of its area) is not counted.
#ifndef STEREODET_EVAL_VOC_MATCHER_INTERNAL_H_
#define STEREODET_EVAL_VOC_MATCHER_INTERNAL_H_

#include <vector>

#include "stereodet/eval/association.h"
#include "stereodet/eval/curves.h"
#include "stereodet/eval/frame_data_internal.h"

namespace stereodet {

// Appends the frame's curve events; since VOC decides each detection in score order, the counts at
// any threshold are those of the prefix of detections above it.
// Returns `append_to` with them appended.
std::vector<CurveEvent> VocFrameEvents(const ClassFrame& frame, Difficulty difficulty,
                                       std::vector<CurveEvent> append_to = {});

// The association at `threshold`. `reuse` lends its memory to the result (its contents are
// discarded).
FrameAssociation VocAssociate(const ClassFrame& frame, Difficulty difficulty, double threshold,
                              FrameAssociation reuse = {});

}  // namespace stereodet

#endif  // STEREODET_EVAL_VOC_MATCHER_INTERNAL_H_
