// Internal to the eval module (used by Evaluate, its tests and benchmarks; not by other modules).
//
// The BEV and 3D overlaps of KITTI's devkit (evaluate_object.cpp: groundBoxOverlap and
// box3DOverlap) in the devkit's own arithmetic, for the rare overlaps whose decision depends on it
// (see KittiOverlapAtThreshold, frame_data.h). boost::geometry 1.74 computes intersections and
// unions on coordinates rescaled to an integer grid (about 1e7 steps across the two boxes), so its
// overlaps differ from exact ones by up to ~1e-6, and in a few degenerate configurations (nested
// footprints with parallel edges) it loses the intersection altogether. Everywhere else
// KittiOverlap (frame_data.h, exact clipping) is used: about 70 times as fast (0.14 us against
// ~10 us in BEV).
//
// What is reproduced, operation by operation (all in double, no fused multiply-add):
//  - a footprint is the closed polygon of the object-frame corners (l/2, w/2), (l/2, -w/2),
//    (-l/2, -w/2), (-l/2, w/2), each turned by R = [[cos ry, sin ry], [-sin ry, cos ry]] as a
//    2x2-by-2x4 matrix product (each entry 0 + R(r,0) * corner_x + R(r,1) * corner_z, summed left
//    to right), then shifted by the camera-frame (x, z); the first corner is repeated at the end,
//    and the ring goes to boost::geometry as it is (clockwise when l, w > 0 or l, w < 0; not
//    corrected otherwise);
//  - the intersection area is boost::geometry::area of the first polygon of
//    boost::geometry::intersection(label footprint, detection footprint), 0 if there is none;
//  - BEV, union criterion: intersection / boost::geometry::area of the first polygon of
//    boost::geometry::union_(label footprint, detection footprint), not area + area -
//    intersection; own-size criterion: intersection / boost::geometry::area(detection footprint);
//  - 3D: the intersection area times max(0, min(y_d, y_l) - max(y_d - h_d, y_l - h_l)); union
//    criterion: that / (h_d * l_d * w_d + h_l * l_l * w_l - that); own-size: that / (h_d * l_d *
//    w_d).
// Bit for bit the devkit built with boost 1.74 (Debian 12) and g++ -O2 on x86-64: checked against
// the devkit's own functions on 1.6 million overlaps. The arithmetic is the installed boost's, so
// it follows a devkit built against the same boost; later boost versions dropped the rescaling (off
// by default by 1.86), and a devkit built against them rounds otherwise.
#ifndef STEREODET_EVAL_DEVKIT_OVERLAP_INTERNAL_H_
#define STEREODET_EVAL_DEVKIT_OVERLAP_INTERNAL_H_

#include <optional>

#include "stereodet/eval/eval_options.h"
#include "stereodet/geometry/box.h"

namespace stereodet {

// The devkit's overlap criteria.
enum class DevkitCriterion {
  kUnion,          // criterion -1: intersection over union (a detection against a label)
  kDetectionSize,  // criterion 0: intersection over the detection's own area / volume (DontCare)
};

// The devkit's BEV (`kind` kBev) or 3D (k3D) overlap of `detection` with `label` (or a DontCare
// region), boxes in the rectified camera frame, metres and radians. A value in [0, 1] for proper
// boxes; not clamped (the devkit's value, whatever it is). Returns nullopt where the devkit has no
// answer: in BEV, when boost returns no union polygon (the devkit reads the first element of the
// empty result and crashes; this happens for a degenerate footprint, l or w zero, or one of them
// negative and the other positive, that overlaps the other box), and when boost throws (uncaught
// in the devkit). Requires: kind is kBev or k3D (throws std::invalid_argument for k2D, whose devkit
// arithmetic is KittiOverlap's own). Each thread keeps boost's results for its last pairs (up to
// 65,536; BEV and 3D share a pair's intersection), so asking again costs a look-up.
std::optional<double> DevkitBoxOverlap(OverlapKind kind, DevkitCriterion criterion,
                                       const Box3D& detection, const Box3D& label);

}  // namespace stereodet

#endif  // STEREODET_EVAL_DEVKIT_OVERLAP_INTERNAL_H_
