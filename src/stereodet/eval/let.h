// Longitudinal-error-tolerant overlaps (LET-3D-AP; Hung et al., "Let-3D-AP: longitudinal error
// tolerant 3D average precision for camera-only 3D detection", 2022, and Waymo Open Dataset's
// camera-only 3D detection metric): a camera or stereo detector's depth error grows with range, so
// LET-3D-AP forgives a box's error *along the sensor's line of sight* within a tolerance that grows
// with the label's range, and LET-3D-APL weighs each true positive by how far inside that tolerance
// it lies. Definitions, units and what is measured against Waymo's implementation:
// docs/metrics.md, "LET-3D-AP".
//
// Frames: every box in the rectified camera frame of the labels (x right, y down, z forward, m;
// Box3D::location the bottom centre), the sensor at LetOptions::sensor_m in that frame. A box's
// position on its line of sight is that of its centre (Box3D::Centre()), as in Waymo's metric.
#ifndef STEREODET_EVAL_LET_H_
#define STEREODET_EVAL_LET_H_

#include "stereodet/eval/eval_options.h"
#include "stereodet/geometry/box.h"

namespace stereodet {

// LetOptions (the tolerance and the sensor) is in eval_options.h, as EvalOptions::let.

// The longitudinal affinity of a detection to a label, in [0, 1]: 1 - |e| / tolerance clamped to
// [0, 1], with e = |P| cos(angle(P, G)) - |G| the detection centre's range error projected on the
// label's line of sight (P, G the detection's and label's centres relative to the sensor) and the
// tolerance of LetOptions at |G|. A detection on the label's line of sight 1 m beyond a label 20 m
// away has e = 1 m, tolerance 2 m, affinity 0.5. Ranges below 1e-9 m are taken as 1e-9 m (a box
// at the sensor has no line of sight).
double LongitudinalAffinity(const Box3D& detection, const Box3D& label, const LetOptions& options);

// The detection moved along its own line of sight to the point closest to the label's centre:
// its centre P becomes (P . G / |P|^2) P (relative to the sensor), its size and rotation kept
// (Waymo's TYPE_RANGE_ALIGNED). The returned box's location is its bottom centre, as every Box3D's.
Box3D RangeAlignedBox(const Box3D& detection, const Box3D& label, const LetOptions& options);

// LET-IoU: KittiBoxOverlap(kind) of RangeAlignedBox(detection, label) with the label (kind kBev or
// k3D, or kLetBev / kLet3D for the same; std::invalid_argument otherwise). A pair matches under LET
// when this is at least the class's threshold and LongitudinalAffinity is above 0.
double LetOverlap(OverlapKind kind, const Box3D& detection, const Box3D& label,
                  const LetOptions& options);

}  // namespace stereodet

#endif  // STEREODET_EVAL_LET_H_
