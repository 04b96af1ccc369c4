// Internal to the eval module: what a stable filter or a breakdown bin (breakdown.h) keeps of one
// frame's ClassFrame, read once per frame and object instead of once per association tallied
// against it (a frame is tallied at each of its scores, each difficulty, and by four passes: its
// valid labels, its operating point, its Brier terms, its curve).
#ifndef STEREODET_EVAL_SELECTION_MASK_INTERNAL_H_
#define STEREODET_EVAL_SELECTION_MASK_INTERNAL_H_

#include <cstddef>
#include <cstdint>
#include <vector>

#include "stereodet/eval/breakdown.h"
#include "stereodet/eval/frame_data.h"

namespace stereodet {

// A selection on one ClassFrame, by the ClassFrame's label and detection indices: label[i] and
// det[j] are 1 where the selection keeps label i / detection j alone (KeepsLabel, KeepsDetection);
// a TP pair is kept by its label alone (a bin) or by both (a filter: `pair_needs_det`). The arrays
// belong to a BinMasks, which must outlive the view.
struct MaskView {
  const uint8_t* label = nullptr;
  const uint8_t* det = nullptr;
  bool pair_needs_det = false;

  bool KeepsLabel(int i) const { return label[i] != 0; }
  bool KeepsDetection(int j) const { return det[j] != 0; }
  bool KeepsPair(int i, int j) const { return label[i] != 0 && (!pair_needs_det || det[j] != 0); }
};

// The masks of several selections (a cell's breakdown bins, or one filter) on one ClassFrame, in
// one array per side: selection s keeps label i where label[s * num_labels + i] is 1.
struct BinMasks {
  std::vector<uint8_t> label, det;
  int num_labels = 0, num_dets = 0;
  bool pair_needs_det = false;  // the selections are filters (all of them, or none)

  MaskView Bin(size_t s) const {
    return {label.data() + s * static_cast<size_t>(num_labels),
            det.data() + s * static_cast<size_t>(num_dets), pair_needs_det};
  }
};

// The masks of `selections` on `cf`, prepared from `frame`: each object is read once for all of
// them. Precondition: the selections are all filters or all bins.
BinMasks MaskBins(const EvalFrame& frame, const ClassFrame& cf,
                  const std::vector<StableSelection>& selections);
// The mask of one selection (null: everything kept) on `cf`: its Bin(0).
BinMasks MaskSelection(const EvalFrame& frame, const ClassFrame& cf,
                       const StableSelection* selection);

}  // namespace stereodet

#endif  // STEREODET_EVAL_SELECTION_MASK_INTERNAL_H_
