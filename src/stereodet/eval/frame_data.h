// One frame's labels and detections and the overlap functions of KITTI's devkit. The per-frame,
// per-class, per-overlap-kind data every matcher works on (ClassFrame) is internal to the eval
// module: frame_data_internal.h.
#ifndef STEREODET_EVAL_FRAME_DATA_H_
#define STEREODET_EVAL_FRAME_DATA_H_

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
//   2D:  intersection / (area(det) + area(label) - intersection), boxes as given (no +1), in the
//        devkit's own arithmetic;
//   BEV: rotated-rectangle intersection of the (x, z) footprints / union (the devkit uses
//        boost::geometry; we use the exact clipping of geometry::BevIntersectionArea, which agrees
//        with the devkit's value to ~1e-6 but not bit for bit: see KittiOverlapAtThreshold in
//        frame_data_internal.h);
//   3D:  BEV intersection * max(0, min(y_d, y_l) - max(y_d - h_d, y_l - h_l)) /
//        (h_d l_d w_d + h_l l_l w_l - intersection).
// A footprint with both l and w negative (KITTI's -1 "not estimated") is the same square as with
// |l|, |w| (the devkit's polygon); a footprint with one non-positive side has no area (the devkit
// crashes on it when it overlaps a label). `kind` 2D, BEV or 3D (std::invalid_argument for a LET
// kind, which needs LetOptions: MatchOverlap).
double KittiOverlap(OverlapKind kind, const Object& detection, const Object& label);
// The overlap a match is decided on: KittiOverlap for 2D, BEV and 3D; for kLetBev / kLet3D the
// LET-IoU (LetOverlap, let.h) where the longitudinal affinity is above 0, else 0 (outside the
// tolerance no pair matches, however well its aligned box overlaps).
double MatchOverlap(OverlapKind kind, const Object& detection, const Object& label,
                    const LetOptions& let);
// KittiOverlap's BEV or 3D value of two boxes (`kind` kBev or k3D; std::invalid_argument
// otherwise).
double KittiBoxOverlap(OverlapKind kind, const Box3D& detection, const Box3D& label);
// The devkit's DontCare test (criterion 0): the intersection over the detection's own area (2D),
// footprint (BEV) or volume (3D). KITTI's DontCare rows carry 3D fields of -1 / -1000: in BEV their
// footprint is a 1 m x 1 m square at (x, z) = (-1000, -1000), exactly that of a detection whose 3D
// was not estimated (own-area overlap 1), so in BEV they suppress such detections, as the devkit
// does; in 3D (height -1, no volume) they suppress nothing. A LET kind tests as its plain kind
// (PlainKind): DontCare regions are not moved.
double KittiDontCareOverlap(OverlapKind kind, const Object& detection, const Object& dontcare);

// Whether KITTI's official devkit would evaluate `spec` for `kind` given these detections: some
// detection of the class with left >= 0 (2D); x, z != -1000 and w, l > 0 (BEV); x, y, z != -1000
// and h, w, l > 0 (3D, and both LET kinds: the affinity needs the box's centre).
bool HasEvaluableDetection(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                           OverlapKind kind);
// False if any detection (any class) has alpha == -10: the devkit then skips AOS altogether.
bool AllAlphasValid(const std::vector<EvalFrame>& frames);

}  // namespace stereodet

#endif  // STEREODET_EVAL_FRAME_DATA_H_
