#include "stereodet/eval/association.h"

#include <algorithm>

namespace stereodet {

int64_t FrameAssociation::CountLabels(Outcome o) const {
  return std::count(label_outcome.begin(), label_outcome.end(), o);
}

int64_t FrameAssociation::CountDets(Outcome o) const {
  return std::count(det_outcome.begin(), det_outcome.end(), o);
}

}  // namespace stereodet
