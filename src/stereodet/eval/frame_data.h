// One frame's labels and detections, the overlap functions of KITTI's devkit, and the per-frame,
// per-class, per-overlap-kind data every matcher works on (computed once, reused for all
// difficulties and all score thresholds).
#ifndef STEREODET_EVAL_FRAME_DATA_H_
#define STEREODET_EVAL_FRAME_DATA_H_

#include <cstdint>
#include <string>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/kitti/object.h"

namespace stereodet {

// A frame as read from a label file and a detection file, each in file order. Every detection has
// a score.
struct EvalFrame {
  std::string id;
  std::vector<Object> labels;
  std::vector<Object> detections;
};

// Overlap of a detection with a label as KITTI's devkit computes it (criterion -1, "union"):
//   2D:  intersection / (area(det) + area(label) - intersection), boxes as given (no +1);
//   BEV: rotated-rectangle intersection of the (x, z) footprints / union (the devkit uses
//        boost::geometry; we use the exact clipping of geometry::BevIntersectionArea);
//   3D:  BEV intersection * max(0, min(y_d, y_l) - max(y_d - h_d, y_l - h_l)) /
//        (h_d l_d w_d + h_l l_l w_l - intersection).
// A footprint with both l and w negative (KITTI's -1 "not estimated") is the same square as with
// |l|, |w| (the devkit's polygon); a footprint with one non-positive side has no area.
double KittiOverlap(OverlapKind kind, const Object& detection, const Object& label);
// The devkit's DontCare test (criterion 0): the intersection over the detection's own area (2D),
// footprint (BEV) or volume (3D). KITTI's DontCare rows carry 3D fields of -1 / -1000, so in BEV
// and 3D they suppress nothing, exactly as in the devkit.
double KittiDontCareOverlap(OverlapKind kind, const Object& detection, const Object& dontcare);

// The labels that concern one class (the class and its neighbours, file order), the detections that
// may take part (the class, plus any detection lower than 40 px, which KITTI's devkit treats as an
// "ignored" detection whatever its class), and the overlaps >= the class threshold between them.
struct ClassFrame {
  // Labels: the class or a neighbour class, in file order.
  std::vector<int32_t> label_object;      // index into EvalFrame::labels
  std::vector<uint8_t> label_neighbour;   // 1 for a neighbour class (always ignored)
  std::vector<uint8_t> label_difficulty;  // bit d set if the label meets difficulty d
  std::vector<double> label_alpha;
  // Detections: the class, or 2D height < 40 px (any class), in file order.
  std::vector<int32_t> det_object;     // index into EvalFrame::detections
  std::vector<uint8_t> det_is_class;   // 1 if of the evaluated class
  std::vector<double> det_height;      // |bottom - top|, px
  std::vector<double> det_score;
  std::vector<double> det_alpha;
  std::vector<uint8_t> det_dontcare;   // overlaps a DontCare region by > the threshold (criterion 0)
  // Overlaps >= min_overlap, by label (CSR): label i's edges are [edge_begin[i], edge_begin[i+1]),
  // in ascending detection order.
  std::vector<int32_t> edge_begin;
  std::vector<int32_t> edge_det;
  std::vector<double> edge_overlap;
  double min_overlap = 0.5;

  int num_labels() const { return static_cast<int>(label_object.size()); }
  int num_dets() const { return static_cast<int>(det_object.size()); }
  bool LabelValid(int i, Difficulty d) const {
    return !label_neighbour[i] && (label_difficulty[i] >> static_cast<int>(d) & 1);
  }
};

// Builds the ClassFrame of `frame` for `spec` and `kind`. Requires: every detection has a score.
ClassFrame PrepareClassFrame(const EvalFrame& frame, const ClassSpec& spec, OverlapKind kind);

// Whether the devkit would evaluate `spec` for `kind` given these detections (a detection of the
// class with left >= 0 for 2D, x != -1000 for BEV, y != -1000 for 3D).
bool HasEvaluableDetection(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                           OverlapKind kind);
// False if any detection (any class) has alpha == -10: the devkit then skips AOS altogether.
bool AllAlphasValid(const std::vector<EvalFrame>& frames);

}  // namespace stereodet

#endif  // STEREODET_EVAL_FRAME_DATA_H_
