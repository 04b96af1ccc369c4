// `--compat openpcdet`: what OpenPCDet's (and mmdetection3d's) kitti_object_eval_python computes
// where it differs from KITTI's devkit. See docs/metrics.md, "OpenPCDet / mmdetection3d
// compatibility", for the table of differences and how they were verified.
//
// Only the pieces that differ live here and in openpcdet_compat_internal.h: the rotated-box overlap
// (a port of its numba kernel rotate_iou.py, float32 included), the preparation of a class frame
// with its label, detection and DontCare rules, its AOS switch (internal), its classes and its
// printout (here). The matching (pass 1, getThresholds, pass 2) is the devkit's and is shared with
// `--matcher kitti` (kitti_matcher_internal.h).
#ifndef STEREODET_EVAL_OPENPCDET_COMPAT_H_
#define STEREODET_EVAL_OPENPCDET_COMPAT_H_

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
