// `--compat openpcdet`: what OpenPCDet's (and mmdetection3d's) kitti_object_eval_python computes
// where it differs from KITTI's devkit. See docs/metrics.md, "OpenPCDet / mmdetection3d
// compatibility", for the table of differences and how they were verified.
//
// Only the pieces that differ live here: the rotated-box overlap (a port of its numba kernel
// rotate_iou.py, float32 included), the preparation of a class frame with its label, detection and
// DontCare rules, its AOS switch, and its printout. The matching (pass 1, getThresholds, pass 2) is
// the devkit's and is shared with `--matcher kitti` (kitti_matcher.h).
#ifndef STEREODET_EVAL_OPENPCDET_COMPAT_H_
#define STEREODET_EVAL_OPENPCDET_COMPAT_H_

#include <array>
#include <string>
#include <vector>

#include "stereodet/eval/eval_options.h"
#include "stereodet/eval/frame_data.h"

namespace stereodet {

struct EvalResult;

// get_official_eval_result's classes and overlaps (min_overlaps[set][2D, BEV, 3D]): strict Car 0.7,
// Pedestrian 0.5, Cyclist 0.5, Van 0.7, Person_sitting 0.5, Truck 0.7 in all three kinds; loose
// (`loose`) 2D as strict but Truck 0.5, BEV and 3D 0.5 / 0.25 / 0.25 / 0.5 / 0.25 / 0.5. Neighbours
// as the devkit (Car: Van, Pedestrian: Person_sitting). Throws std::invalid_argument for another
// class name (the tool has no overlap for it).
ClassSpec OpenPcdetClassSpec(const std::string& name, bool loose = false);

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
// past its local array); `overflow`, if given, is set then.
double PcdetIntersectionArea(const PcdetRotatedBox& rbox1, const PcdetRotatedBox& rbox2,
                             bool* overflow = nullptr);

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
void OpenPcdetEnvelope(std::array<double, 41>* curve);

// get_official_eval_result's printout for `classes` (Car, Pedestrian, Cyclist, ...): per class the
// strict set (AP, AP_R40) then the loose one, "bbox/bev/3d AP:%.4f, %.4f, %.4f" and
// "aos  AP:%.2f, ..." when AOS is computed. `strict` and `loose` hold the class x kind x difficulty
// results (2D, BEV and 3D; Easy, Moderate and Hard) of the two overlap sets; a missing figure is
// printed as nan.
std::string FormatOpenPcdetResult(const EvalResult& strict, const EvalResult& loose);

// What get_official_eval_result(gt, dt, classes) prints for these frames: evaluates the classes of
// `options` (by name) with OpenPcdetClassSpec's strict and loose overlaps, 2D / BEV / 3D, Easy /
// Moderate / Hard, compat kOpenPcdet, and formats them (FormatOpenPcdetResult). `options` gives the
// class names and num_threads; its other fields are not used.
std::string OpenPcdetPrintout(const std::vector<EvalFrame>& frames, const EvalOptions& options);

}  // namespace stereodet

#endif  // STEREODET_EVAL_OPENPCDET_COMPAT_H_
