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
  Profile(double k, double centre, double half, double slope)
      : k(k),
        centre(centre),
        half(half),
        slope(slope),
        lin(-0.5 * k * CurveSlope(-centre, half) + slope),
        con(-0.5 * k * Curve(-centre, half)) {}
  double k, centre, half, slope;
  double lin, con;  // P(u) = (k / 2) q(u - centre) + lin u + con
  double Value(double u) const {
    return 0.5 * k *
               (Curve(u - centre, half) - Curve(-centre, half) - CurveSlope(-centre, half) * u) +
           slope * u;
  }
  // Value and Derivative at once.
  double ValueAndDerivative(double u, double* derivative) const {
    if (k == 0.0) {
      *derivative = slope;
      return slope * u;
    }
    const double s = u - centre;
    if (s >= -half && s <= half) {
      *derivative = k * s + lin;
      return 0.5 * k * s * s + lin * u + con;
    }
    const double sign = s > 0 ? 1.0 : -1.0;
    *derivative = k * half * sign + lin;
    return 0.5 * k * (2.0 * half * sign * s - half * half) + lin * u + con;
  }
  double Derivative(double u) const {
    return 0.5 * k * (CurveSlope(u - centre, half) - CurveSlope(-centre, half)) + slope;
  }
  // P(u0 + t du) as c2 t^2 + c1 t + c0 on the piece `state` (-1: before the curve, 0: on it, 1:
  // after it), added to c.
  void Polynomial(double u0, double du, int state, double c[3]) const {
    const double s0 = u0 - centre;  // s(t) = s0 + t du
    if (state == 0) {
      c[2] += 0.5 * k * du * du;
      c[1] += k * s0 * du;
      c[0] += 0.5 * k * s0 * s0;
    } else {
      const double sign = state;
      c[1] += k * half * sign * du;
      c[0] += 0.5 * k * (2.0 * half * sign * s0 - half * half);
    }
    c[1] += lin * du;
    c[0] += lin * u0 + con;
  }
  // A piecewise-linear upper bound U(u) >= P(u): m_plus u for u > 0, m_minus u for u < 0. A
  // convex P (k > 0) lies below the straight grades' slopes (P(0) = 0, P' increasing), a concave
  // one below its tangent at 0. U is convex either way.
  double UpperBound(double u) const {
    if (k <= 0.0) return slope * u;
    return u > 0 ? (lin + k * half) * u : (lin - k * half) * u;
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
  const double m = std::sqrt(dr * dr + df * df);
  const double theta = std::atan2(s * df, -s * dr);
  return {static_cast<float>(s * (radius - m)), static_cast<float>(s * theta * radius)};
}

float ArcLateral(const Eigen::Vector2f& origin_xz, const Eigen::Vector2f& forward_xz,
                 float curvature_per_m, float x, float z) {
  const Eigen::Vector2f right(forward_xz.y(), -forward_xz.x());
  const Eigen::Vector2f d(x - origin_xz.x(), z - origin_xz.y());
  if (std::abs(curvature_per_m) < kStraight) return d.dot(right);
  const double k = curvature_per_m, s = k > 0 ? 1.0 : -1.0, radius = 1.0 / std::abs(k);
  const double dr = d.dot(right) - s * radius, df = d.dot(forward_xz);
  return static_cast<float>(s * (radius - std::sqrt(dr * dr + df * df)));
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

double GroundProfile::HeightAndNormal(double x, double z, Eigen::Vector3f* normal) const {
  if (Flat()) {
    *normal = Eigen::Vector3f(0.0f, -1.0f, 0.0f);
    return 0.0;
  }
  const Eigen::Vector2d la = Frame(x, z);
  const Profile along = AlongProfile(*this), lateral = LateralProfile(*this);
  double dl, da;
  const double height =
      along.ValueAndDerivative(la.y(), &da) + lateral.ValueAndDerivative(la.x(), &dl);
  const double gx = dl * forward_xz.y() + da * forward_xz.x();
  const double gz = -dl * forward_xz.x() + da * forward_xz.y();
  const double inv = 1.0 / std::sqrt(gx * gx + 1.0 + gz * gz);
  *normal = Eigen::Vector3f(static_cast<float>(-gx * inv), static_cast<float>(-inv),
                            static_cast<float>(-gz * inv));
  return height;
}

float GroundProfile::Intersect(const Ray& ray, float base_y_m, float t_min, float t_max) const {
  if (Flat()) {
    if (ray.direction.y() <= 0.0f) return kNoHit;
    const float t = (base_y_m - ray.origin.y()) / ray.direction.y();
    return t > t_min && t < t_max ? t : kNoHit;
  }
  const Eigen::Vector3d o = ray.origin.cast<double>(), d = ray.direction.cast<double>();
  const double rx = forward_xz.y(), rz = -forward_xz.x();  // right
  const double ox = o.x() - origin_xz.x(), oz = o.z() - origin_xz.y();
  const double l0 = ox * rx + oz * rz, dl = d.x() * rx + d.z() * rz;
  const double a0 = ox * forward_xz.x() + oz * forward_xz.y();
  const double da = d.x() * forward_xz.x() + d.z() * forward_xz.y();
  const Profile along = AlongProfile(*this), lateral = LateralProfile(*this);
  // Cheap rejection: F(t) = base - y(t) - Height(t) >= B(t) = base - y(t) - U_a(a(t)) -
  // U_l(l(t)) with the profiles' upper bounds, and B is concave in t: a ray with B > 0 at both ends
  // of (t_min, t_max) stays above the ground. Most rays above the horizon end here.
  if (std::isfinite(t_max)) {
    const auto bound = [&](double t) {
      return base_y_m - o.y() - t * d.y() - along.UpperBound(a0 + t * da) -
             lateral.UpperBound(l0 + t * dl);
    };
    if (bound(t_min) > 0.0 && bound(t_max) > 0.0) return kNoHit;
  }
  // Walk the pieces of the ray (where each profile is on its curve, state 0, or on the straight
  // grade before (-1) or after (+1) it) from t_min. Along a ray each state changes monotonically,
  // so a root whose states are the piece's lies in the piece; only when a piece holds no root is
  // its end (a division) computed.
  const auto state = [](double s, double half) { return s < -half ? -1 : (s > half ? 1 : 0); };
  int state_a = along.k != 0.0 ? state(a0 + t_min * da - along.centre, along.half) : 0;
  int state_l = lateral.k != 0.0 ? state(l0 + t_min * dl - lateral.centre, lateral.half) : 0;
  double lo = t_min;
  for (int piece = 0; piece < 5; ++piece) {
    // F(t) = base - y(t) - Height(t) = q2 t^2 + q1 t + q0 on this piece: positive above the ground.
    double c[3] = {0.0, 0.0, 0.0};
    along.Polynomial(a0, da, state_a, c);
    lateral.Polynomial(l0, dl, state_l, c);
    const double q2 = -c[2], q1 = -d.y() - c[1], q0 = base_y_m - o.y() - c[0];
    double root = kNoHit;  // the smallest root above lo
    if (q2 == 0.0) {
      if (q1 != 0.0) {
        const double t = -q0 / q1;
        if (t > lo) root = t;
      }
    } else {
      const double disc = q1 * q1 - 4.0 * q2 * q0;
      if (disc >= 0.0) {
        const double sq = std::sqrt(disc);
        const double qq = -0.5 * (q1 + (q1 >= 0 ? sq : -sq));  // the stable form
        const double r1 = qq / q2, r2 = qq != 0.0 ? q0 / qq : r1;
        const double first = std::min(r1, r2), second = std::max(r1, r2);
        root = first > lo ? first : (second > lo ? second : kNoHit);
      }
    }
    if (root != kNoHit &&
        (along.k == 0.0 || state(a0 + root * da - along.centre, along.half) == state_a) &&
        (lateral.k == 0.0 || state(l0 + root * dl - lateral.centre, lateral.half) == state_l)) {
      return root < t_max ? static_cast<float>(root) : kNoHit;  // the first crossing
    }
    // The piece's end: the next break of either profile.
    const auto next_break = [lo](const Profile& p, double u0, double du, int st) {
      if (p.k == 0.0 || du == 0.0) return static_cast<double>(kNoHit);
      if ((du > 0 && st == 1) || (du < 0 && st == -1)) return static_cast<double>(kNoHit);
      // Moving up s: from before the curve to its start, from the curve to its end; down: back.
      const double target = du > 0 ? (st == -1 ? -p.half : p.half) : (st == 1 ? p.half : -p.half);
      return std::max(lo, (p.centre + target - u0) / du);
    };
    const double ta = next_break(along, a0, da, state_a);
    const double tl = next_break(lateral, l0, dl, state_l);
    const double hi = std::min(ta, tl);
    if (hi >= t_max) return kNoHit;
    if (ta == hi) state_a += da > 0 ? 1 : -1;
    if (tl == hi) state_l += dl > 0 ? 1 : -1;
    lo = hi;
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
