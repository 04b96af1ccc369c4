// Internal to the eval module: the pieces of `--compat openpcdet` that Evaluate uses (see
// openpcdet_compat.h).
#ifndef STEREODET_EVAL_OPENPCDET_COMPAT_INTERNAL_H_
#define STEREODET_EVAL_OPENPCDET_COMPAT_INTERNAL_H_

#include <array>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/geometry/box.h"

namespace stereodet {

// A footprint as rotate_iou.py takes it: centre (x, z), length along the box's x, width,
// rotation_y. The kernel turns the five numbers to float32 first.
struct PcdetRotatedBox {
  double x = 0, z = 0, l = 0, w = 0, rotation_y = 0;
};
PcdetRotatedBox PcdetFootprint(const Box3D& box);  // (x, z, l, w, rotation_y) of a KITTI box

// rotate_iou.py's inter(rbox1, rbox2): the intersection area of two footprints as the kernel
// computes it, reproducing the arithmetic of its run under the CUDA simulator
// (NUMBA_ENABLE_CUDASIM=1, numpy scalars: float32 corners and polygon, float64 where numpy
// promotes) bit for bit. It is not the true area: identical or nearly identical footprints often
// lose corners to float32 rounding (identical KITTI-sized footprints come out 0, a third or all of
// their area), and a point at the polygon's centre gives NaN. Returns NaN also when the clipped
// polygon would exceed the kernel's 8 points (the simulator raises IndexError there, a GPU writes
// past its local array).
double PcdetIntersectionArea(const PcdetRotatedBox& rbox1, const PcdetRotatedBox& rbox2);

// The overlap kitti_object_eval_python stores for a detection and a label (its
// calculate_iou_partly):
//   2D:  iw * ih / (area(det) + area(label) - iw * ih), float64 (the devkit's own, see
//   KittiOverlap); BEV: float32(inter / (float32(l_l w_l + l_d w_d) - inter)), inter =
//   PcdetIntersectionArea(label,
//        detection);
//   3D:  with inter = float32(PcdetIntersectionArea(label, detection)) and the y overlap iw of the
//   two
//        boxes (as the devkit): iw * inter / (l_d h_d w_d + l_l h_l w_l - iw * inter) if iw > 0 and
//        inter > 0, else 0 (NaN stays NaN).
double PcdetOverlap(OverlapKind kind, const Object& detection, const Object& label);

// PrepareClassFrame under OpenPCDet's rules (its clean_data): a label is ignored at a difficulty
// when its height is <= the minimum (the official devkit's rule); DontCare regions are the labels
// named exactly "DontCare" (case-sensitive) and suppress false positives in 2D only; overlaps are
// PcdetOverlap's. Detections and neighbour classes as the devkit. `reuse` lends its memory, as in
// PrepareClassFrame. Requires: every detection has a score.
ClassFrame PrepareClassFrameOpenPcdet(const EvalFrame& frame, const ClassSpec& spec,
                                      OverlapKind kind, ClassFrame reuse = {});

// OpenPCDet's AOS switch: on iff the first detection of the first frame that has detections has
// alpha != -10 (the others are not looked at). False when there is no detection at all.
bool OpenPcdetComputesAos(const std::vector<EvalFrame>& frames);

// The envelope of a 41-slot curve as numpy takes it: slot i = max over slots i..40, NaN if any of
// them is NaN (np.max propagates NaN; the devkit's loop does not).
std::array<double, 41> OpenPcdetEnvelope(std::array<double, 41> curve);

}  // namespace stereodet

#endif  // STEREODET_EVAL_OPENPCDET_COMPAT_INTERNAL_H_
