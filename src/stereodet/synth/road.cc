#include "stereodet/synth/road.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "stereodet/geometry/calibration.h"
#include "stereodet/synth/scene.h"

namespace stereodet {

namespace {

// Below this curvature (a radius of 10 000 km) an arc is treated as straight.
constexpr double kStraight = 1e-7;

// A C1 curve between two straight grades: (k / 2) q(s) with q(s) = s^2 on |s| <= half, and
// 2 half |s| - half^2 beyond.
double Curve(double s, double half) {
  const double m = std::abs(s);
  return m <= half ? s * s : 2.0 * half * m - half * half;
}
double CurveSlope(double s, double half) {
  return std::abs(s) <= half ? 2.0 * s : (s > 0 ? 2.0 * half : -2.0 * half);
}

// One profile P(u) = (k / 2) [q(u - centre) - q(-centre) - q'(-centre) u] + slope u: 0 and `slope`
// at u = 0.
struct Profile {
  double k, centre, half, slope;
  double Value(double u) const {
    return 0.5 * k *
               (Curve(u - centre, half) - Curve(-centre, half) - CurveSlope(-centre, half) * u) +
           slope * u;
  }
  double Derivative(double u) const {
    return 0.5 * k * (CurveSlope(u - centre, half) - CurveSlope(-centre, half)) + slope;
  }
  // P(u0 + t du) as c2 t^2 + c1 t + c0 on the piece that holds u(t_mid).
  void Polynomial(double u0, double du, double t_mid, double c[3]) const {
    const double s_mid = u0 + t_mid * du - centre;
    const double lin = -0.5 * k * CurveSlope(-centre, half) + slope;  // coefficient of u
    const double con = -0.5 * k * Curve(-centre, half);
    const double s0 = u0 - centre;  // s(t) = s0 + t du
    if (std::abs(s_mid) <= half) {
      c[2] += 0.5 * k * du * du;
      c[1] += 0.5 * k * 2.0 * s0 * du;
      c[0] += 0.5 * k * s0 * s0;
    } else {
      const double sign = s_mid > 0 ? 1.0 : -1.0;
      c[1] += 0.5 * k * 2.0 * half * sign * du;
      c[0] += 0.5 * k * (2.0 * half * sign * s0 - half * half);
    }
    c[1] += lin * du;
    c[0] += lin * u0 + con;
  }
  // The largest |P'(u)| (P' is monotonic: it is largest at one of the straight grades).
  double MaxSlope() const {
    const double base = -0.5 * k * CurveSlope(-centre, half) + slope;
    return std::max(std::abs(base - k * half), std::abs(base + k * half));
  }
  // Ray parameters where u0 + t du crosses a break of the curve.
  int Breaks(double u0, double du, double out[2]) const {
    if (k == 0.0 || du == 0.0) return 0;
    out[0] = (centre - half - u0) / du;
    out[1] = (centre + half - u0) / du;
    return 2;
  }
};

Profile AlongProfile(const GroundProfile& g) {
  return {g.vertical_curvature_per_m, g.vertical_centre_m, g.vertical_half_length_m, g.pitch};
}
Profile LateralProfile(const GroundProfile& g) {
  return {g.crown_curvature_per_m, g.crown_lateral_m, g.crown_half_width_m, g.roll};
}

}  // namespace

Eigen::Vector2f ArcToRoad(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                          float curvature_per_m, float x, float z) {
  const Eigen::Vector2f right(forward_xz.y(), -forward_xz.x());
  const Eigen::Vector2f d(x - origin_xz.x(), z - origin_xz.y());
  if (std::abs(curvature_per_m) < kStraight) return {d.dot(right), d.dot(forward_xz)};
  // The arc's centre lies at `radius` to the right (left for a negative curvature) of the origin.
  // In double: the radius is large and the lateral offset its small difference from the distance.
  const double k = curvature_per_m, s = k > 0 ? 1.0 : -1.0, radius = 1.0 / std::abs(k);
  const double dr = d.dot(right) - s * radius, df = d.dot(forward_xz);
  const double m = std::hypot(dr, df);
  const double theta = std::atan2(s * df, -s * dr);
  return {static_cast<float>(s * (radius - m)), static_cast<float>(s * theta * radius)};
}

Eigen::Vector2f ArcFromRoad(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                            float curvature_per_m, float lateral_m, float along_m) {
  const Eigen::Vector2f right(forward_xz.y(), -forward_xz.x());
  if (std::abs(curvature_per_m) < kStraight) {
    return origin_xz + lateral_m * right + along_m * forward_xz;
  }
  // The heading at `along` is the origin's turned right by theta = k along; the point is at
  // lateral - 1/k along the turned right vector from the centre origin + right / k.
  const double k = curvature_per_m, theta = k * along_m;
  const double c = std::cos(theta), sn = std::sin(theta);
  const Eigen::Vector2d r0 = right.cast<double>(), f0 = forward_xz.cast<double>();
  const Eigen::Vector2d right_at = c * r0 - sn * f0;
  const Eigen::Vector2d centre = origin_xz.cast<double>() + r0 / k;
  return (centre + (lateral_m - 1.0 / k) * right_at).cast<float>();
}

Eigen::Vector2d GroundProfile::Frame(double x, double z) const {
  const Eigen::Vector2d d(x - origin_xz.x(), z - origin_xz.y());
  const Eigen::Vector2d right(forward_xz.y(), -forward_xz.x());
  return {d.dot(right), d.dot(forward_xz)};
}

double GroundProfile::Height(double x, double z) const {
  if (Flat()) return 0.0;
  const Eigen::Vector2d la = Frame(x, z);
  return AlongProfile(*this).Value(la.y()) + LateralProfile(*this).Value(la.x());
}

Eigen::Vector2d GroundProfile::Gradient(double x, double z) const {
  if (Flat()) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d la = Frame(x, z);
  const double dl = LateralProfile(*this).Derivative(la.x());
  const double da = AlongProfile(*this).Derivative(la.y());
  const Eigen::Vector2d right(forward_xz.y(), -forward_xz.x());
  return dl * right + da * forward_xz;
}

Eigen::Vector3f GroundProfile::Normal(double x, double z) const {
  if (Flat()) return Eigen::Vector3f(0.0f, -1.0f, 0.0f);
  // The surface y - base + Height(x, z) = 0 has the gradient (dH/dx, 1, dH/dz); up is its negative.
  const Eigen::Vector2d g = Gradient(x, z);
  return -Eigen::Vector3d(g.x(), 1.0, g.y()).normalized().cast<float>();
}

float GroundProfile::Intersect(const Ray& ray, float base_y_m, float t_min, float t_max) const {
  if (Flat()) {
    if (ray.direction.y() <= 0.0f) return kNoHit;
    const float t = (base_y_m - ray.origin.y()) / ray.direction.y();
    return t > t_min && t < t_max ? t : kNoHit;
  }
  const Eigen::Vector3d o = ray.origin.cast<double>(), d = ray.direction.cast<double>();
  const Eigen::Vector2d right(forward_xz.y(), -forward_xz.x());
  const Eigen::Vector2d od(o.x() - origin_xz.x(), o.z() - origin_xz.y());
  const Eigen::Vector2d dd(d.x(), d.z());
  const double l0 = od.dot(right), dl = dd.dot(right);
  const double a0 = od.dot(forward_xz), da = dd.dot(forward_xz);
  const Profile along = AlongProfile(*this), lateral = LateralProfile(*this);
  // Cheap rejection: |Height| <= s_a |a| + s_l |l| (P(0) = 0), so F(t) = base - y(t) - Height(t)
  // >= c0 + c1 t with the constants below; a ray with F's bound positive at both ends of (t_min,
  // t_max) stays above the ground. Most rays above the horizon end here.
  {
    const double sa = along.MaxSlope(), sl = lateral.MaxSlope();
    const double c0 = base_y_m - o.y() - sa * std::abs(a0) - sl * std::abs(l0);
    const double c1 = -d.y() - sa * std::abs(da) - sl * std::abs(dl);
    if (c0 > 0.0 && (c1 >= 0.0 || (std::isfinite(t_max) && c0 + c1 * t_max > 0.0))) return kNoHit;
  }
  // Pieces of the ray between the curves' breaks.
  std::array<double, 6> ts;
  int n = 0;
  ts[n++] = t_min;
  double b[2];
  for (int i = 0, m = along.Breaks(a0, da, b); i < m; ++i) {
    if (b[i] > t_min && b[i] < t_max) ts[n++] = b[i];
  }
  for (int i = 0, m = lateral.Breaks(l0, dl, b); i < m; ++i) {
    if (b[i] > t_min && b[i] < t_max) ts[n++] = b[i];
  }
  for (int i = 2; i < n; ++i) {  // insertion sort of the (at most four) breaks
    for (int j = i; j > 1 && ts[j] < ts[j - 1]; --j) std::swap(ts[j], ts[j - 1]);
  }
  // Far pieces of a ray with an infinite t_max: a finite end for the midpoint test.
  const double t_end = std::isfinite(t_max) ? t_max : std::max(1e6, 2.0 * ts[n - 1] + 1.0);
  for (int piece = 0; piece < n; ++piece) {
    const double lo = ts[piece], hi = piece + 1 < n ? ts[piece + 1] : t_end;
    if (hi <= lo) continue;
    const double mid = 0.5 * (lo + hi);
    // F(t) = base - y(t) - Height(t): positive above the ground.
    double c[3] = {0.0, 0.0, 0.0};
    along.Polynomial(a0, da, mid, c);
    lateral.Polynomial(l0, dl, mid, c);
    const double q2 = -c[2], q1 = -d.y() - c[1], q0 = base_y_m - o.y() - c[0];
    // Smallest root in (lo, hi].
    double roots[2];
    int count = 0;
    if (std::abs(q2) < 1e-15) {
      if (q1 != 0.0) roots[count++] = -q0 / q1;
    } else {
      const double disc = q1 * q1 - 4.0 * q2 * q0;
      if (disc >= 0.0) {
        const double sq = std::sqrt(disc);
        const double qq = -0.5 * (q1 + (q1 >= 0 ? sq : -sq));  // stable form
        const double r1 = qq / q2, r2 = qq != 0.0 ? q0 / qq : r1;
        roots[count++] = std::min(r1, r2);
        roots[count++] = std::max(r1, r2);
      }
    }
    for (int i = 0; i < count; ++i) {
      const double t = roots[i];
      if (t > lo && t <= hi && t > t_min && t < t_max) return static_cast<float>(t);
    }
  }
  return kNoHit;
}

Eigen::Vector4d TrueGroundPlane(const Scene& scene, const Calibration& calib, int width,
                                int height) {
  if (scene.ground.Flat()) return {0.0, -1.0, 0.0, scene.ground_y_m};
  // The stereo fit's region (GroundPlaneOptions' defaults).
  constexpr double kRoiFraction = 0.5, kMinDepth = 3.0, kMaxDepth = 20.0, kMaxLateral = 6.0;
  constexpr int kStep = 4;
  const Matrix34d& p = calib.projection[2];
  const double fx = p(0, 0), fy = p(1, 1), cx = p(0, 2), cy = p(1, 2);
  const Eigen::Vector3d centre = calib.CameraCentreInRect(2);
  const int first_row =
      std::clamp(static_cast<int>(std::floor(height * (1.0 - kRoiFraction))), 0, height - 1);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int n = 0;
  for (int v = first_row; v < height; v += kStep) {
    for (int u = 0; u < width; u += kStep) {
      const Ray ray(centre.cast<float>(), Eigen::Vector3f(static_cast<float>((u - cx) / fx),
                                                          static_cast<float>((v - cy) / fy), 1.0f));
      const float t = scene.ground.Intersect(ray, scene.ground_y_m, 1e-3f, kNoHit);
      if (t == kNoHit || t < kMinDepth || t > kMaxDepth) continue;  // t is the depth (z = 1)
      Eigen::Vector3d x = ray.At(t).cast<double>();
      x.y() = scene.ground_y_m - scene.ground.Height(x.x(), x.z());
      if (std::abs(x.x() - centre.x()) > kMaxLateral) continue;
      sum += x;
      outer += x * x.transpose();
      ++n;
    }
  }
  if (n < 3) {  // nothing of the ground in view: its tangent plane under the camera
    const Eigen::Vector3d up = scene.ground.Normal(0.0, 0.0).cast<double>();
    return {up.x(), up.y(), up.z(), -up.y() * scene.ground_y_m};
  }
  // Total least squares: the normal is the covariance's eigenvector of the smallest eigenvalue.
  const Eigen::Vector3d mean = sum / n;
  const Eigen::Matrix3d cov = outer / n - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.y() > 0) normal = -normal;
  return {normal.x(), normal.y(), normal.z(), -normal.dot(mean)};
}

}  // namespace stereodet
