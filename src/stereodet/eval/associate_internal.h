// Internal to the eval module: the association of one frame with any matcher.
#ifndef STEREODET_EVAL_ASSOCIATE_INTERNAL_H_
#define STEREODET_EVAL_ASSOCIATE_INTERNAL_H_

#include "stereodet/eval/association.h"
#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data_internal.h"

namespace stereodet {

// The association at `threshold` of one frame with `matcher` (KittiAssociate, OptimalAssociate or
// VocAssociate). `reuse` lends its memory to the result (its contents are discarded).
FrameAssociation Associate(Matcher matcher, const ClassFrame& frame, Difficulty difficulty,
                           double threshold, FrameAssociation reuse = {});

}  // namespace stereodet

#endif  // STEREODET_EVAL_ASSOCIATE_INTERNAL_H_
