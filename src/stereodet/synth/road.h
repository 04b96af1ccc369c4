// Road geometry of the synthetic scenes: the horizontal alignment (a circular arc: straight roads
// and gentle bends), side streets, and the shape of the ground (grade changes with crest or sag,
// a crowned cross-section with crossfall, the car's pitch and roll on its springs).
//
// The ground is the height field y_rect = base_y - Height(x, z) (y points down, so a positive
// height is above the ground under the camera). Height is a sum of two one-dimensional profiles,
// each C1 and piecewise quadratic (a parabolic curve between two straight grades), in the
// coordinates of a straight frame through the camera: `a` along the road's heading at the camera,
// `l` to its right. Along a ray both are linear in the ray parameter, so the height is piecewise
// quadratic in it and a ray meets the ground where one of at most five quadratics has its
// smallest root: closed form and exact (GroundProfile::Intersect), with no iteration.
#ifndef STEREODET_SYNTH_ROAD_H_
#define STEREODET_SYNTH_ROAD_H_

#include <Eigen/Core>
#include <cmath>

#include "stereodet/synth/shapes.h"

namespace stereodet {

struct Calibration;
struct Scene;

// A side street crossing (or joining, on one side) the road at right angles.
struct SideStreet {
  float along_m = 40.0f;      // centre, road coordinate
  float half_width_m = 4.0f;  // half the width of its carriageway
  bool left = true;           // it opens to the left of the road ...
  bool right = true;          // ... and to its right
  bool Covers(float along_m) const { return std::abs(along_m - this->along_m) <= half_width_m; }
  bool OnSide(int side) const { return side == 0 ? left : right; }  // 0: left, 1: right
};

// Road coordinates on a circular arc: the road's lateral-0 line passes through `origin_xz` with
// heading `forward_xz` (unit) and curves to the right by `curvature_per_m` (1 / radius; negative:
// to the left; 0: straight). `lateral` is metres to the right of that line (along the radius),
// `along` the arc length. Exact both ways for |lateral| below the radius.
Eigen::Vector2f ArcToRoad(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                          float curvature_per_m, float x, float z);
float ArcLateral(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                 float curvature_per_m, float x, float z);  // ArcToRoad's lateral alone
Eigen::Vector2f ArcFromRoad(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                            float curvature_per_m, float lateral_m, float along_m);

// The height field of the ground; the default is flat (the plane y = base_y).
struct GroundProfile {
  // The straight frame of the profile: the camera's point on the road and the road's heading there.
  Eigen::Vector2d origin_xz = Eigen::Vector2d::Zero();
  Eigen::Vector2d forward_xz = Eigen::Vector2d(0.0, 1.0);
  // Slopes of the ground at the origin relative to the camera (dh/da, dh/dl): the car's pitch
  // and roll on its springs. Positive pitch: the ground rises ahead.
  double pitch = 0.0;
  double roll = 0.0;
  // Vertical curve: second derivative of the height along the road (1/m; > 0 sag, < 0 crest) on
  // |a - vertical_centre_m| <= vertical_half_length_m, straight grades beyond.
  double vertical_curvature_per_m = 0.0;
  double vertical_centre_m = 40.0;
  double vertical_half_length_m = 50.0;
  // Cross-section: second derivative of the height across the road (< 0: crowned, falling to both
  // sides) on |l - crown_lateral_m| <= crown_half_width_m, straight crossfall beyond.
  double crown_curvature_per_m = 0.0;
  double crown_lateral_m = 0.0;
  double crown_half_width_m = 3.5;

  bool Flat() const {
    return pitch == 0.0 && roll == 0.0 && vertical_curvature_per_m == 0.0 &&
           crown_curvature_per_m == 0.0;
  }
  // Profile coordinates (l, a) of a rect (x, z) point.
  Eigen::Vector2d Frame(double x, double z) const;
  // Height above the ground under the camera (metres, up) at rect (x, z): 0 at the origin.
  double Height(double x, double z) const;
  // (dHeight/dx, dHeight/dz) at rect (x, z).
  Eigen::Vector2d Gradient(double x, double z) const;
  // Unit normal pointing up (rect y < 0) at rect (x, z).
  Eigen::Vector3f Normal(double x, double z) const;
  // Height and Normal at once (one evaluation of the frame and the profiles).
  double HeightAndNormal(double x, double z, Eigen::Vector3f* normal) const;
  // Smallest t in (t_min, t_max) where `ray` meets the ground y = base_y - Height(x, z), or kNoHit.
  // The ray must start above the ground.
  float Intersect(const Ray& ray, float base_y_m, float t_min, float t_max) const;
};

// The least-squares plane of the true ground (the surface only, whatever stands on it) over the
// region the stereo ground fit samples (stereo/reprojection.h's GroundPlaneOptions defaults): the
// rays of camera 2's pixels in the lower half of a width x height image, every 4th row and
// column, that meet the ground at a depth of 3-20 m within 6 m of camera 2's vertical plane.
// Returns (a, b, c, d) with a x + b y + c z + d = 0, unit normal up (b < 0). On a flat ground it
// is the ground's plane exactly.
Eigen::Vector4d TrueGroundPlane(const Scene& scene, const Calibration& calib, int width,
                                int height);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_ROAD_H_
