// Intersection over union of 2D, bird's-eye-view and 3D boxes.
//
// All functions return a value in [0, 1], never NaN: boxes with zero area (or volume) give 0, boxes
// that only touch give 0, and a box compared with itself gives exactly 1. BEV intersections are
// exact rotated-rectangle clipping in double precision (no rasterization, no polygon library).
#ifndef STEREODET_GEOMETRY_IOU_H_
#define STEREODET_GEOMETRY_IOU_H_

#include "stereodet/geometry/box.h"

namespace stereodet {

// Area of the intersection of two axis-aligned boxes (px^2).
double IntersectionArea(const Box2D& a, const Box2D& b);
// Axis-aligned IoU: intersection / (area a + area b - intersection).
double Iou2D(const Box2D& a, const Box2D& b);

// Area (m^2) of the intersection of the BEV footprints of two 3D boxes (the rotated rectangles
// given by location.x, location.z, l, w and rotation_y; heights are ignored).
double BevIntersectionArea(const Box3D& a, const Box3D& b);
// BEV IoU: footprint intersection / footprint union.
double BevIou(const Box3D& a, const Box3D& b);

// Volume (m^3) of the intersection: BEV intersection times the overlap of the y extents
// [location.y - h, location.y].
double IntersectionVolume(const Box3D& a, const Box3D& b);
// 3D IoU: intersection volume / (volume a + volume b - intersection volume), as KITTI's devkit.
double Iou3D(const Box3D& a, const Box3D& b);

}  // namespace stereodet

#endif  // STEREODET_GEOMETRY_IOU_H_
