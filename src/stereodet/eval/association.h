// The outcome of matching one frame for one class, at one score threshold: what each label and each
// detection counts as. Produced by every matcher; consumed by the operating-point statistics, the
// filters, the Brier scores, calibration and the localization error.
#ifndef STEREODET_EVAL_ASSOCIATION_H_
#define STEREODET_EVAL_ASSOCIATION_H_

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace stereodet {

enum class Outcome : int8_t {
  kNone = 0,  // takes no part (a detection of another class, or below the score threshold)
  kTp,        // a true positive (label or detection of a matched pair)
  kFp,        // a detection that counts as a false positive
  kFn,        // a label that counts as a false negative
  kIgnored,   // neither: an ignored label/detection, or one excused by an ignored one
  kDontCare,  // a detection that would be a false positive but lies in a DontCare region (excused)
};
// "none", "tp", "fp", "fn", "ignored", "dontcare".
const char* OutcomeName(Outcome outcome);
std::optional<Outcome> ParseOutcome(std::string_view text);

// Indices are those of the ClassFrame the association was computed on.
struct FrameAssociation {
  std::vector<Outcome> label_outcome;  // kTp, kFn or kIgnored
  std::vector<int32_t> label_det;      // the detection of a kTp label, else -1
  std::vector<Outcome> det_outcome;    // kTp, kFp, kIgnored, kDontCare or kNone
  std::vector<int32_t> det_label;      // the label of a kTp detection, else -1

  int64_t CountLabels(Outcome o) const;
  int64_t CountDets(Outcome o) const;
};

}  // namespace stereodet

#endif  // STEREODET_EVAL_ASSOCIATION_H_
