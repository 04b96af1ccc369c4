// Boxes: 2D boxes in image pixels and 3D boxes in the KITTI rectified camera frame.
//
// Frames and units:
//  - Image: x right, y down, pixels; a Box2D spans [left, right] x [top, bottom] (KITTI's
//  convention
//    of continuous coordinates; width = right - left, no +1).
//  - Rectified camera frame (KITTI's "camera coordinates", the rectified frame of camera 0): x
//  right,
//    y down, z forward, metres. A Box3D's `location` is the centre of its bottom face; h, w, l are
//    its extents along the object's y, z and x axes; `rotation_y` (radians) turns the object about
//    the camera's y axis, 0 = facing the camera's x axis (the object's length along +x).
//  - Bird's-eye view (BEV): the (x, z) ground plane of the camera frame, looked at from above.
#ifndef STEREODET_GEOMETRY_BOX_H_
#define STEREODET_GEOMETRY_BOX_H_

#include <Eigen/Core>
#include <array>

namespace stereodet {

struct Box2D {
  double left = 0.0;    // px
  double top = 0.0;     // px
  double right = 0.0;   // px
  double bottom = 0.0;  // px

  double Width() const { return right - left; }
  double Height() const { return bottom - top; }
  // 0 for inverted or empty boxes, never negative.
  double Area() const;
  bool operator==(const Box2D&) const = default;
};

struct Box3D {
  double h = 0.0, w = 0.0, l = 0.0;                    // metres
  Eigen::Vector3d location = Eigen::Vector3d::Zero();  // bottom centre, rectified camera frame, m
  double rotation_y = 0.0;                             // radians about the camera's y axis

  double Volume() const { return h * w * l; }
  // Centre of the box (not its bottom face), rectified camera frame.
  Eigen::Vector3d Centre() const { return location - Eigen::Vector3d(0.0, h / 2.0, 0.0); }
  bool operator==(const Box3D&) const = default;
};

// A point of the BEV plane: (x, z) of the camera frame, metres.
using BevPoint = Eigen::Vector2d;

// The 8 corners of `box` in the camera frame, in KITTI's devkit order: the bottom face
// (y = location.y) first, at object-frame (x, z) = (l/2, w/2), (l/2, -w/2), (-l/2, -w/2), (-l/2,
// w/2) (clockwise in the (x, z) plane drawn with x right and z up), then the top face in the same
// order. Column i is corner i.
Eigen::Matrix<double, 3, 8> Corners(const Box3D& box);

// The BEV footprint: the 4 bottom corners' (x, z), in the same order as Corners().
std::array<BevPoint, 4> BevCorners(const Box3D& box);

}  // namespace stereodet

#endif  // STEREODET_GEOMETRY_BOX_H_
