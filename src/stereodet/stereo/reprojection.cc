#include "stereodet/stereo/reprojection.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "stereodet/stereo/disparity.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

void CheckDisparityImage(const cv::Mat& disparity_px) {
  STEREODET_CHECK(disparity_px.type() == CV_32FC1)
      << "disparity must be CV_32FC1 pixels, got type " << disparity_px.type();
}

// Unit normal pointing up in the rect frame (y down), i.e. with a negative y component.
Eigen::Vector3d OrientUp(const Eigen::Vector3d& normal) {
  return normal.y() > 0 ? Eigen::Vector3d(-normal) : normal;
}

double TiltDeg(const Eigen::Vector3d& up_normal) {
  return std::acos(std::clamp(-up_normal.y(), -1.0, 1.0)) * 180.0 / M_PI;
}

}  // namespace

StereoGeometry StereoGeometry::FromCalibration(const Calibration& calib) {
  calib.CheckStereo();
  StereoGeometry geometry;
  geometry.focal_px = calib.FocalPx();
  geometry.baseline_m = calib.BaselineM();
  STEREODET_CHECK(geometry.baseline_m > 0)
      << "calibration: camera 3 must be right of camera 2 (baseline " << geometry.baseline_m
      << " m)";
  const Eigen::Vector2d principal = calib.PrincipalPointPx();
  geometry.cx_px = principal.x();
  geometry.cy_px = principal.y();
  geometry.camera2_in_rect = calib.CameraCentreInRect(2);
  geometry.velo_from_rect = calib.VeloFromRect();
  return geometry;
}

StereoGeometry StereoGeometry::Scaled(double scale_x, double scale_y) const {
  STEREODET_CHECK(scale_x > 0 && scale_y > 0 && std::isfinite(scale_x) && std::isfinite(scale_y))
      << "geometry scale must be > 0, got " << scale_x << ", " << scale_y;
  StereoGeometry scaled = *this;
  scaled.focal_px = focal_px * scale_x;
  scaled.focal_y_px = FocalY() * scale_y;
  scaled.cx_px = (cx_px + 0.5) * scale_x - 0.5;
  scaled.cy_px = (cy_px + 0.5) * scale_y - 0.5;
  return scaled;
}

Eigen::Vector3d StereoGeometry::PointInRect(double u_px, double v_px, double disparity_px) const {
  const double z = DepthFromDisparity(disparity_px);
  return camera2_in_rect +
         z * Eigen::Vector3d((u_px - cx_px) / focal_px, (v_px - cy_px) / FocalY(), 1.0);
}

cv::Mat DepthFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry) {
  CheckDisparityImage(disparity_px);
  cv::Mat depth(disparity_px.size(), CV_32FC1);
  for (int v = 0; v < depth.rows; ++v) {
    const float* d = disparity_px.ptr<float>(v);
    float* z = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      z[u] = IsValidDisparity(d[u]) ? static_cast<float>(geometry.DepthFromDisparity(d[u])) : kNaN;
    }
  }
  return depth;
}

cv::Mat PointsInRectFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry) {
  CheckDisparityImage(disparity_px);
  cv::Mat points(disparity_px.size(), CV_32FC3);
  for (int v = 0; v < points.rows; ++v) {
    const float* d = disparity_px.ptr<float>(v);
    cv::Vec3f* out = points.ptr<cv::Vec3f>(v);
    for (int u = 0; u < points.cols; ++u) {
      if (IsValidDisparity(d[u])) {
        const Eigen::Vector3d x = geometry.PointInRect(u, v, d[u]);
        out[u] = cv::Vec3f(static_cast<float>(x.x()), static_cast<float>(x.y()),
                           static_cast<float>(x.z()));
      } else {
        out[u] = cv::Vec3f(kNaN, kNaN, kNaN);
      }
    }
  }
  return points;
}

GroundPlane GroundPlane::Nominal(double camera_height_m) {
  GroundPlane plane;
  plane.normal_in_rect = Eigen::Vector3d(0.0, -1.0, 0.0);
  plane.offset_m = camera_height_m;
  return plane;
}

void GroundPlaneOptions::Check() const {
  STEREODET_CHECK(roi_fraction > 0 && roi_fraction <= 1)
      << "ground roi_fraction must be in (0, 1], got " << roi_fraction;
  STEREODET_CHECK(sample_step_px >= 1) << "ground sample_step_px must be >= 1";
  STEREODET_CHECK(min_depth_m >= 0 && max_depth_m > min_depth_m)
      << "ground depth range must satisfy 0 <= min < max";
  STEREODET_CHECK(max_lateral_m >= 0) << "ground max_lateral_m must be >= 0";
  STEREODET_CHECK(max_samples >= 3) << "ground max_samples must be >= 3";
  STEREODET_CHECK(iterations >= 1) << "ground iterations must be >= 1";
  STEREODET_CHECK(inlier_threshold_m > 0) << "ground inlier_threshold_m must be > 0";
  STEREODET_CHECK(min_inliers >= 3) << "ground min_inliers must be >= 3";
  STEREODET_CHECK(min_inlier_fraction >= 0 && min_inlier_fraction <= 1)
      << "ground min_inlier_fraction must be in [0, 1]";
  STEREODET_CHECK(max_tilt_deg >= 0 && max_tilt_deg < 90)
      << "ground max_tilt_deg must be in [0, 90)";
  STEREODET_CHECK(min_camera_height_m < max_camera_height_m)
      << "ground camera height range is empty";
  STEREODET_CHECK(nominal_camera_height_m > 0 && nominal_camera_height_m < 100)
      << "nominal camera height must be in (0, 100) m, got " << nominal_camera_height_m;
  STEREODET_CHECK(warn_tilt_deg >= 0 && warn_tilt_deg < 90)
      << "ground warn_tilt_deg must be in [0, 90), got " << warn_tilt_deg;
  STEREODET_CHECK(warn_camera_height_m >= 0 && warn_camera_height_m < 100)
      << "ground warn_camera_height_m must be in [0, 100), got " << warn_camera_height_m;
}

GroundPlaneFit FitGroundPlane(const cv::Mat& disparity_px, const StereoGeometry& geometry,
                              const GroundPlaneOptions& options) {
  options.Check();
  STEREODET_CHECK(disparity_px.type() == CV_32FC1 || disparity_px.type() == CV_16SC1)
      << "ground fit needs CV_32FC1 disparity or OpenCV's CV_16SC1 (x16), got type "
      << disparity_px.type();
  GroundPlaneFit fit;
  fit.plane = GroundPlane::Nominal(options.nominal_camera_height_m);
  fit.camera_height_m = options.nominal_camera_height_m;
  if (!options.enabled) {
    fit.reason = "ground fit disabled";
    return fit;
  }

  // Sample a grid of the lower image. Thinning a grid keeps the sample spread over the whole road,
  // which a random subset would too, but deterministically and without a second pass.
  const int first_row =
      std::clamp(static_cast<int>(std::floor(disparity_px.rows * (1.0 - options.roi_fraction))), 0,
                 disparity_px.rows - 1);
  const double min_disparity = geometry.DisparityFromDepth(options.max_depth_m);
  const double max_disparity = options.min_depth_m > 0
                                   ? geometry.DisparityFromDepth(options.min_depth_m)
                                   : std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> points;
  const bool fixed_point = disparity_px.type() == CV_16SC1;
  for (int v = first_row; v < disparity_px.rows; v += options.sample_step_px) {
    for (int u = 0; u < disparity_px.cols; u += options.sample_step_px) {
      const float d = fixed_point ? disparity_px.ptr<int16_t>(v)[u] * (1.0f / 16.0f)
                                  : disparity_px.ptr<float>(v)[u];
      if (IsValidDisparity(d) && d >= min_disparity && d <= max_disparity) {
        const Eigen::Vector3d point = geometry.PointInRect(u, v, d);
        if (options.max_lateral_m > 0 &&
            std::abs(point.x() - geometry.camera2_in_rect.x()) > options.max_lateral_m) {
          continue;
        }
        points.push_back(point);
      }
    }
  }
  if (static_cast<int>(points.size()) > options.max_samples) {
    std::vector<Eigen::Vector3d> thinned;
    thinned.reserve(options.max_samples);
    const double stride = static_cast<double>(points.size()) / options.max_samples;
    for (int i = 0; i < options.max_samples; ++i) {
      thinned.push_back(points[static_cast<size_t>(i * stride)]);
    }
    points.swap(thinned);
  }
  const int n = static_cast<int>(points.size());
  fit.samples = n;
  if (n < options.min_inliers) {
    fit.reason = "too few stereo points on the lower image (" + std::to_string(n) + " < " +
                 std::to_string(options.min_inliers) + ")";
    return fit;
  }

  const double max_tilt_cos = std::cos(options.max_tilt_deg * M_PI / 180.0);
  // Inlier counting is the inner loop of RANSAC: on float arrays it vectorizes (a few centimetres
  // of threshold need no double precision).
  std::vector<float> xs(n), ys(n), zs(n);
  for (int i = 0; i < n; ++i) {
    xs[i] = static_cast<float>(points[i].x());
    ys[i] = static_cast<float>(points[i].y());
    zs[i] = static_cast<float>(points[i].z());
  }
  const float threshold = static_cast<float>(options.inlier_threshold_m);
  auto count_inliers = [&](const Eigen::Vector3d& normal, double offset) {
    const float a = static_cast<float>(normal.x()), b = static_cast<float>(normal.y()),
                c = static_cast<float>(normal.z()), d = static_cast<float>(offset);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      count += std::abs(a * xs[i] + b * ys[i] + c * zs[i] + d) < threshold ? 1 : 0;
    }
    return count;
  };
  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  int best_count = 0;
  Eigen::Vector3d best_normal = fit.plane.normal_in_rect;
  double best_offset = fit.plane.offset_m;
  for (int iteration = 0; iteration < options.iterations; ++iteration) {
    const int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    Eigen::Vector3d normal = (points[b] - points[a]).cross(points[c] - points[a]);
    const double norm = normal.norm();
    if (norm < 1e-9) continue;
    normal = OrientUp(normal / norm);
    // Hypotheses far from horizontal (walls, car sides) are rejected before counting: cheap, and it
    // stops a large vertical surface from winning.
    if (-normal.y() < max_tilt_cos) continue;
    const double offset = -normal.dot(points[a]);
    const int count = count_inliers(normal, offset);
    if (count > best_count) {
      best_count = count;
      best_normal = normal;
      best_offset = offset;
    }
  }
  if (best_count < 3) {
    fit.reason = "no near-horizontal plane found";
    return fit;
  }

  // Least-squares refinement on the inliers: the plane through their centroid whose normal is the
  // direction of least variance.
  Eigen::Vector3d normal = best_normal;
  double offset = best_offset;
  for (int refinement = 0; refinement < 2; ++refinement) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int count = 0;
    for (const Eigen::Vector3d& p : points) {
      if (std::abs(normal.dot(p) + offset) < options.inlier_threshold_m) {
        centroid += p;
        ++count;
      }
    }
    if (count < 3) break;
    centroid /= count;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& p : points) {
      if (std::abs(normal.dot(p) + offset) < options.inlier_threshold_m) {
        const Eigen::Vector3d q = p - centroid;
        covariance += q * q.transpose();
      }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
    normal = OrientUp(solver.eigenvectors().col(0).normalized());
    offset = -normal.dot(centroid);
  }
  const int inliers = count_inliers(normal, offset);
  const double tilt = TiltDeg(normal);

  fit.tilt_deg = tilt;
  fit.camera_height_m = offset;
  if (inliers < options.min_inliers) {
    fit.reason = "too few ground inliers (" + std::to_string(inliers) + " < " +
                 std::to_string(options.min_inliers) + ")";
  } else if (inliers < options.min_inlier_fraction * n) {
    fit.reason = "ground inlier fraction " + std::to_string(static_cast<double>(inliers) / n) +
                 " below " + std::to_string(options.min_inlier_fraction);
  } else if (tilt > options.max_tilt_deg) {
    fit.reason = "ground plane tilted " + std::to_string(tilt) + " deg";
  } else if (offset < options.min_camera_height_m || offset > options.max_camera_height_m) {
    fit.reason = "camera height " + std::to_string(offset) + " m outside [" +
                 std::to_string(options.min_camera_height_m) + ", " +
                 std::to_string(options.max_camera_height_m) + "]";
  } else {
    fit.suspect = tilt > options.warn_tilt_deg ||
                  std::abs(offset - options.nominal_camera_height_m) > options.warn_camera_height_m;
    if (!fit.suspect || !options.suspect_uses_prior) {
      fit.fitted = true;
      fit.reason = "fitted";
      fit.inliers = inliers;
      fit.plane.normal_in_rect = normal;
      fit.plane.offset_m = offset;
      return fit;
    }
    fit.reason = fmt::format(
        "suspect fit (tilt {:.3f} deg, camera height {:.4f} m, {} of {} inliers), nominal prior "
        "used",
        tilt, offset, inliers, n);
  }
  // Fallback: report the rejected fit's numbers but use the nominal plane.
  fit.camera_height_m = options.nominal_camera_height_m;
  return fit;
}

cv::Mat HeightFromDisparity(const cv::Mat& disparity_px, const StereoGeometry& geometry,
                            const GroundPlane& plane) {
  CheckDisparityImage(disparity_px);
  cv::Mat height(disparity_px.size(), CV_32FC1);
  for (int v = 0; v < height.rows; ++v) {
    const float* d = disparity_px.ptr<float>(v);
    float* h = height.ptr<float>(v);
    for (int u = 0; u < height.cols; ++u) {
      h[u] = IsValidDisparity(d[u])
                 ? static_cast<float>(plane.HeightAbove(geometry.PointInRect(u, v, d[u])))
                 : kNaN;
    }
  }
  return height;
}

void HeightQuantization::Check() const {
  STEREODET_CHECK(std::isfinite(min_m) && std::isfinite(max_m) && min_m < max_m)
      << "height quantization range must satisfy min < max, got [" << min_m << ", " << max_m << "]";
}

uint16_t HeightQuantization::Quantize(double height_m) const {
  if (std::isnan(height_m)) return 0;
  const double t = (std::clamp(height_m, min_m, max_m) - min_m) / (max_m - min_m);
  return static_cast<uint16_t>(1 + std::lround(t * (kLevels - 1)));
}

double HeightQuantization::Dequantize(uint16_t code) const {
  if (code == 0) return std::numeric_limits<double>::quiet_NaN();
  return min_m + (code - 1) * (max_m - min_m) / (kLevels - 1);
}

void DepthQuantization::Check() const {
  STEREODET_CHECK(std::isfinite(min_m) && std::isfinite(max_m) && min_m >= 0 && min_m < max_m)
      << "depth quantization range must satisfy 0 <= min < max, got [" << min_m << ", " << max_m
      << "]";
  STEREODET_CHECK(bits >= 8 && bits <= 16) << "depth bits must be in 8..16, got " << bits;
}

uint16_t DepthQuantization::Quantize(double depth_m) const {
  if (std::isnan(depth_m)) return 0;
  const double t = (std::clamp(depth_m, min_m, max_m) - min_m) / (max_m - min_m);
  return static_cast<uint16_t>(1 + std::lround(t * (MaxCode() - 1)));
}

double DepthQuantization::Dequantize(uint16_t code) const {
  if (code == 0) return std::numeric_limits<double>::quiet_NaN();
  return min_m + (code - 1) * (max_m - min_m) / (MaxCode() - 1);
}

cv::Mat QuantizeHeight(const cv::Mat& height_m, const HeightQuantization& quantization) {
  quantization.Check();
  STEREODET_CHECK(height_m.type() == CV_32FC1) << "height must be CV_32FC1 metres";
  cv::Mat codes(height_m.size(), CV_16UC1);
  for (int v = 0; v < codes.rows; ++v) {
    const float* h = height_m.ptr<float>(v);
    uint16_t* q = codes.ptr<uint16_t>(v);
    for (int u = 0; u < codes.cols; ++u) q[u] = quantization.Quantize(h[u]);
  }
  return codes;
}

cv::Mat QuantizeDepth(const cv::Mat& depth_m, const DepthQuantization& quantization) {
  quantization.Check();
  STEREODET_CHECK(depth_m.type() == CV_32FC1) << "depth must be CV_32FC1 metres";
  cv::Mat codes(depth_m.size(), CV_16UC1);
  for (int v = 0; v < codes.rows; ++v) {
    const float* z = depth_m.ptr<float>(v);
    uint16_t* q = codes.ptr<uint16_t>(v);
    for (int u = 0; u < codes.cols; ++u) q[u] = quantization.Quantize(z[u]);
  }
  return codes;
}

}  // namespace stereodet
