#include <utility>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/voc_matcher_internal.h"

namespace stereodet {

FrameAssociation Associate(Matcher matcher, const ClassFrame& frame, Difficulty difficulty,
                           double threshold, FrameAssociation reuse) {
  switch (matcher) {
    case Matcher::kKitti:
      return KittiAssociate(frame, difficulty, threshold, std::move(reuse));
    case Matcher::kOptimal:
      return OptimalAssociate(frame, difficulty, threshold, std::move(reuse));
    case Matcher::kVoc:
      return VocAssociate(frame, difficulty, threshold, std::move(reuse));
  }
  return {};
}

}  // namespace stereodet
