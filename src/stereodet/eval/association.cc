#include "stereodet/eval/association.h"

#include <algorithm>

namespace stereodet {

const char* OutcomeName(Outcome outcome) {
  switch (outcome) {
    case Outcome::kNone:
      return "none";
    case Outcome::kTp:
      return "tp";
    case Outcome::kFp:
      return "fp";
    case Outcome::kFn:
      return "fn";
    case Outcome::kIgnored:
      return "ignored";
    case Outcome::kDontCare:
      return "dontcare";
  }
  return "none";
}

std::optional<Outcome> ParseOutcome(std::string_view text) {
  for (Outcome o : {Outcome::kNone, Outcome::kTp, Outcome::kFp, Outcome::kFn, Outcome::kIgnored,
                    Outcome::kDontCare}) {
    if (text == OutcomeName(o)) return o;
  }
  return std::nullopt;
}

int64_t FrameAssociation::CountLabels(Outcome o) const {
  return std::count(label_outcome.begin(), label_outcome.end(), o);
}

int64_t FrameAssociation::CountDets(Outcome o) const {
  return std::count(det_outcome.begin(), det_outcome.end(), o);
}

}  // namespace stereodet
