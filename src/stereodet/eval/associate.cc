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

FrameAssociator::FrameAssociator(Matcher matcher, const ClassFrame& frame, Difficulty difficulty)
    : matcher_(matcher), frame_(frame), difficulty_(difficulty) {
  if (matcher == Matcher::kOptimal) optimal_.emplace(frame, difficulty);
}

FrameAssociator::FrameAssociator(const OptimalAssociator& optimal, Difficulty difficulty)
    : matcher_(Matcher::kOptimal),
      frame_(optimal.frame()),
      difficulty_(difficulty),
      optimal_(optimal) {}

FrameAssociation FrameAssociator::At(double threshold, FrameAssociation reuse) const {
  if (optimal_) return optimal_->At(threshold, std::move(reuse));
  return Associate(matcher_, frame_, difficulty_, threshold, std::move(reuse));
}

}  // namespace stereodet
