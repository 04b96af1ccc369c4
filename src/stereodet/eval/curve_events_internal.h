// Internal to the eval module: a frame's curve events (curves.h) taken from the matcher's
// association at each of its scores, where the curve cannot be had incrementally: the AOS of the
// optimal matcher (its pairs may change as the threshold drops) and the stable filter's curves of
// the exact matchers.
#ifndef STEREODET_EVAL_CURVE_EVENTS_INTERNAL_H_
#define STEREODET_EVAL_CURVE_EVENTS_INTERNAL_H_

#include <cstdint>
#include <vector>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/association.h"
#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/curves.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/filter.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/selection_mask_internal.h"

namespace stereodet {

// TP/FP/FN and the TP similarity of one association; with `selection`, the stable filter's or a
// breakdown bin's counts (breakdown.h).
struct Tally {
  int64_t tp = 0, fp = 0, fn = 0;
  double similarity = 0.0;
};

Tally TallyAssociation(const EvalFrame& frame, const ClassFrame& cf, const FrameAssociation& a,
                       const StableSelection* selection);

// TallyAssociation of the first `n_s` selections of `masks` (selection_mask_internal.h) at once,
// added to out[0, n_s): a TP pair counts in a selection that keeps the pair (its label for a bin,
// both for a filter), a FN / FP in one that keeps its label / detection. The association and each
// TP's weight are read once for all; each sum goes in label order.
void TallyBins(const ClassFrame& cf, const FrameAssociation& a, const BinMasks& masks, size_t n_s,
               Tally* out);
// TallyBins' labels' part: the TP pairs (and their similarity) and the FN labels, no FP.
void TallyLabels(const ClassFrame& cf, const FrameAssociation& a, const BinMasks& masks, size_t n_s,
                 Tally* out);
// TallyBins of the association in which no detection takes part (a threshold above every score),
// without making it: with every matcher each valid label is a FN there, and nothing else counts.
void TallyNoDetections(const ClassFrame& cf, Difficulty difficulty, const BinMasks& masks,
                       size_t n_s, Tally* out);

// A frame's curve events and its share of the curve's starting FN count.
struct FrameCurveEvents {
  std::vector<CurveEvent> events;
  int64_t base_fn = 0;  // FN with no detection taken (all valid labels that nothing excuses)
};

// Curve events of one frame derived from the matcher's association at every distinct detection
// score of the frame (exact by construction, one association per distinct score), appended to
// `append_to`. With `selection` non-null the counts are the stable filter's (pairs whose label
// and detection both pass; unmatched labels / detections that pass) or a breakdown bin's
// (breakdown.h); the similarity is that of the
// counted TP pairs, and is left out (0) without `with_aos`. `frame` is the EvalFrame `cf` was
// prepared from.
FrameCurveEvents AssociationEvents(Matcher matcher, const EvalFrame& frame, const ClassFrame& cf,
                                   Difficulty difficulty,
                                   const StableSelection* selection = nullptr, bool with_aos = true,
                                   std::vector<CurveEvent> append_to = {});
// AssociationEvents for several selections at once (breakdown bins, as masks on `cf`): one
// association per distinct score serves them all; out[s] is selection s's, s < num_selections.
std::vector<FrameCurveEvents> AssociationEvents(Matcher matcher, const ClassFrame& cf,
                                                Difficulty difficulty, const BinMasks& masks,
                                                size_t num_selections, bool with_aos);
// The same appended to events[s] (an array of num_selections lists), each selection's base_fn
// added to base_fn[s], from the associations of `associator` (of `cf` at `difficulty`; a caller
// that has built the optimal matcher's graph of the frame for its curve lends it): what a caller
// collecting many frames' events uses, without a list per frame.
void AppendAssociationEvents(const FrameAssociator& associator, const ClassFrame& cf,
                             Difficulty difficulty, const BinMasks& masks, size_t num_selections,
                             bool with_aos, std::vector<CurveEvent>* events, int64_t* base_fn);

// The similarity events (AOS) of the optimal matcher's association on one frame, appended to
// `append_to`: each connected component of the overlap graph on its own, one-label components in
// closed form (the label's best present detection), the others from the association at each of
// their scores (above 256 distinct scores in one component, at 64 of them only, the lowest
// included: the similarity is held between them).
std::vector<CurveEvent> OptimalSimilarityEvents(const EvalFrame& frame, const ClassFrame& cf,
                                                Difficulty difficulty,
                                                std::vector<CurveEvent> append_to = {});

}  // namespace stereodet

#endif  // STEREODET_EVAL_CURVE_EVENTS_INTERNAL_H_
