// Internal to the eval module: the association of one frame with any matcher.
#ifndef STEREODET_EVAL_ASSOCIATE_INTERNAL_H_
#define STEREODET_EVAL_ASSOCIATE_INTERNAL_H_

#include <optional>

#include "stereodet/eval/association.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"

namespace stereodet {

// The association at `threshold` of one frame with `matcher` (KittiAssociate, OptimalAssociate or
// VocAssociate). `reuse` lends its memory to the result (its contents are discarded).
FrameAssociation Associate(Matcher matcher, const ClassFrame& frame, Difficulty difficulty,
                           double threshold, FrameAssociation reuse = {});

// Associate of one frame at many thresholds: with the optimal matcher the overlap graph is built
// once (OptimalAssociator: same thread, no other optimal-matcher call in between); the others
// associate afresh each time. `frame` outlives the object.
class FrameAssociator {
 public:
  FrameAssociator(Matcher matcher, const ClassFrame& frame, Difficulty difficulty);
  // The optimal matcher's, on the graph `optimal` built (its preconditions apply).
  explicit FrameAssociator(const OptimalAssociator& optimal, Difficulty difficulty);
  FrameAssociation At(double threshold, FrameAssociation reuse = {}) const;
  Matcher matcher() const { return matcher_; }

 private:
  Matcher matcher_;
  const ClassFrame& frame_;
  Difficulty difficulty_;
  std::optional<OptimalAssociator> optimal_;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_ASSOCIATE_INTERNAL_H_
