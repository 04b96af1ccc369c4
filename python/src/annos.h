// The annotation dicts of OpenPCDet and mmdetection3d (their kitti_infos "annos" and the
// prediction dicts of generate_prediction_dicts), one per frame, to and from stereodet::Object:
//   name        (N,)   str      class name
//   truncated   (N,)   float    [0, 1]            (detections: not used, may be absent)
//   occluded    (N,)   int      0..3              (detections: not used, may be absent)
//   alpha       (N,)   float    radians
//   bbox        (N, 4) float    left, top, right, bottom, px
//   dimensions  (N, 3) float    l, h, w, m        -- OpenPCDet's order, not the file's h, w, l
//   location    (N, 3) float    x, y, z, rect frame (bottom centre), m
//   rotation_y  (N,)   float    radians
//   score       (N,)   float    detections only (labels: absent, or ignored)
// Other keys (difficulty, gt_boxes_lidar, frame_id, ...) are ignored.
#ifndef STEREODET_PYTHON_ANNOS_H_
#define STEREODET_PYTHON_ANNOS_H_

#include <string>
#include <vector>

#include "common.h"
#include "stereodet/kitti/object.h"

namespace stereodet::python {

// Reads one frame's dict. `what` names it in errors ("dt_annos[3]"). With `detections`, "score"
// is required and "truncated" / "occluded" are optional (0 when absent; a non-integral occluded
// becomes -1, as the detection parser reads it); for labels "occluded" must be integral. Raises
// ValueError for a missing key, a wrong shape or non-numbers. Requires the GIL.
std::vector<Object> ObjectsFromAnnos(py::handle annos, bool detections, const std::string& what);

// One frame's dict of `objects`; "score" when `with_score` (NaN for an object without one).
// Requires the GIL.
py::dict AnnosFromObjects(const std::vector<Object>& objects, bool with_score);

}  // namespace stereodet::python

#endif  // STEREODET_PYTHON_ANNOS_H_
