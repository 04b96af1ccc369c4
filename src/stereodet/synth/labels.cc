#include "stereodet/synth/labels.h"

#include <algorithm>
#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

namespace {

double Round2(double x) { return std::round(x * 100.0) / 100.0; }

// Points whose convex hull is the primitive (boxes: exact; cylinders and ellipsoids: inscribed
// polygons, 16 sides, within 2% of the radius; rounded boxes: points on a 32 x 17 direction grid).
void HullPoints(const Primitive& p, std::vector<Eigen::Vector3d>* out) {
  const Eigen::Matrix3d r = p.world_from_local.cast<double>();
  const Eigen::Vector3d c = p.centre.cast<double>();
  const Eigen::Vector3d h = p.half_extent.cast<double>();
  constexpr int kSides = 16;
  switch (p.kind) {
    case ShapeKind::kBox:
      for (int i = 0; i < 8; ++i) {
        const Eigen::Vector3d s((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1);
        out->push_back(c + r * s.cwiseProduct(h));
      }
      break;
    case ShapeKind::kCylinder:
      for (int k = 0; k < kSides; ++k) {
        const double a = 2.0 * M_PI * k / kSides;
        for (double y : {-h.y(), h.y()}) {
          out->push_back(c + r * Eigen::Vector3d(h.x() * std::cos(a), y, h.x() * std::sin(a)));
        }
      }
      break;
    case ShapeKind::kRoundedBox: {
      // Its boundary along rays from the centre (a convex set is star-shaped about it): 32
      // azimuths x 17 elevations (poles included), each point on the box or the ellipsoid,
      // whichever the ray leaves first. The six face centres are among them, so the hull keeps
      // the tight extent along the local axes.
      const Eigen::Vector3d rc = p.round_centre.cast<double>();
      const Eigen::Vector3d rr = p.round_radii.cast<double>();
      for (int j = 0; j <= 16; ++j) {
        const double elevation = M_PI * (j / 16.0 - 0.5);
        for (int k = 0; k < (j == 0 || j == 16 ? 1 : 2 * kSides); ++k) {
          const double a = M_PI * k / kSides;
          const Eigen::Vector3d u(std::cos(elevation) * std::cos(a), std::sin(elevation),
                                  std::cos(elevation) * std::sin(a));
          double t = 1e18;
          for (int i = 0; i < 3; ++i) {
            if (std::abs(u[i]) > 1e-12) t = std::min(t, h[i] / std::abs(u[i]));
          }
          // Exit of the ray from the origin (inside the ellipsoid) through the ellipsoid.
          const Eigen::Vector3d os = (-rc).cwiseQuotient(rr), ds = u.cwiseQuotient(rr);
          const double qa = ds.squaredNorm(), qb = os.dot(ds), qc = os.squaredNorm() - 1.0;
          t = std::min(t, (-qb + std::sqrt(std::max(0.0, qb * qb - qa * qc))) / qa);
          out->push_back(c + r * (t * u));
        }
      }
      break;
    }
    case ShapeKind::kEllipsoid:
      for (int k = 0; k < kSides; ++k) {
        const double a = 2.0 * M_PI * k / kSides, ca = std::cos(a), sa = std::sin(a);
        out->push_back(c + r * Eigen::Vector3d(h.x() * ca, h.y() * sa, 0.0));
        out->push_back(c + r * Eigen::Vector3d(h.x() * ca, 0.0, h.z() * sa));
        out->push_back(c + r * Eigen::Vector3d(0.0, h.y() * ca, h.z() * sa));
      }
      break;
  }
}

// Bounding box of the projection of an object's parts into camera 2, clipped at the near plane.
// Returns false if nothing is in front of the camera.
bool ProjectObject(const Scene& scene, const SceneObject& object, const Calibration& calib,
                   double near_m, Box2D* box) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < object.num_primitives; ++i) {
    HullPoints(scene.primitives[object.first_primitive + i], &points);
  }
  const Matrix34d& p2 = calib.projection[2];
  // Depth in front of camera 2 is the third row of P2 (affine in the point).
  std::vector<double> depth(points.size());
  for (size_t i = 0; i < points.size(); ++i) depth[i] = p2.row(2).dot(points[i].homogeneous());
  double u0 = 1e18, u1 = -1e18, v0 = 1e18, v1 = -1e18;
  bool any = false;
  const auto add = [&](const Eigen::Vector3d& x) {
    const Eigen::Vector3d h = p2 * x.homogeneous();
    const double u = h.x() / h.z(), v = h.y() / h.z();
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    any = true;
  };
  bool clipped = false;
  for (size_t i = 0; i < points.size(); ++i) {
    if (depth[i] >= near_m) {
      add(points[i]);
    } else {
      clipped = true;
    }
  }
  if (clipped) {
    // The clipped hull is the hull of the points in front and the near-plane crossings of the
    // segments between points on either side.
    for (size_t i = 0; i < points.size(); ++i) {
      if (depth[i] >= near_m) continue;
      for (size_t j = 0; j < points.size(); ++j) {
        if (depth[j] < near_m) continue;
        const double t = (near_m - depth[i]) / (depth[j] - depth[i]);
        add(points[i] + t * (points[j] - points[i]));
      }
    }
  }
  if (!any) return false;
  *box = Box2D{u0, v0, u1, v1};
  return true;
}

}  // namespace

void LabelOptions::Check() const {
  STEREODET_CHECK(visible_fraction_occluded_0 >= visible_fraction_occluded_1 &&
                  visible_fraction_occluded_1 >= visible_fraction_occluded_2 &&
                  visible_fraction_occluded_2 >= 0.0 && visible_fraction_occluded_0 <= 1.0)
      << "occlusion thresholds must satisfy 1 >= t0 >= t1 >= t2 >= 0";
  STEREODET_CHECK(min_visible_pixels >= 0 && min_height_px >= 0 && min_dontcare_height_px >= 0)
      << "pixel thresholds must be non-negative";
  STEREODET_CHECK(max_depth_m > 0) << "max_depth_m must be positive";
  STEREODET_CHECK(max_samples >= 16) << "max_samples must be at least 16, got " << max_samples;
  STEREODET_CHECK(near_plane_m > 0) << "near_plane_m must be positive";
}

std::vector<ObjectVisibility> MeasureVisibility(const Scene& scene, const Calibration& calib,
                                                const cv::Mat& object_id,
                                                const LabelOptions& options) {
  options.Check();
  STEREODET_CHECK(object_id.type() == CV_32SC1) << "object_id must be CV_32SC1";
  const int width = object_id.cols, height = object_id.rows;
  const Matrix34d& p2 = calib.projection[2];
  const double fx = p2(0, 0), fy = p2(1, 1), cx = p2(0, 2), cy = p2(1, 2);
  const Eigen::Vector3f centre = calib.CameraCentreInRect(2).cast<float>();
  std::vector<ObjectVisibility> out;
  for (int index = 0; index < static_cast<int>(scene.objects.size()); ++index) {
    const SceneObject& object = scene.objects[index];
    Box2D box;
    if (!ProjectObject(scene, object, calib, options.near_plane_m, &box)) continue;
    if (box.right < 0 || box.left > width - 1 || box.bottom < 0 || box.top > height - 1) continue;
    ObjectVisibility vis;
    vis.object = index;
    vis.unclipped_box = box;
    vis.box = Box2D{std::max(box.left, 0.0), std::max(box.top, 0.0),
                    std::min(box.right, width - 1.0), std::min(box.bottom, height - 1.0)};
    // Sample the silhouette on a pixel grid (stride s) over the box, limited to a window around
    // the image: the rendered ray of pixel (u, v) is exactly the sample's ray, so the id buffer
    // tells whether the sample is seen.
    const double l = std::max(box.left, -1.0 * width), r = std::min(box.right, 2.0 * width);
    const double t = std::max(box.top, -1.0 * height), b = std::min(box.bottom, 2.0 * height);
    const double area = std::max(1.0, (r - l) * (b - t));
    const int stride =
        std::max(1, static_cast<int>(std::ceil(std::sqrt(area / options.max_samples))));
    const int u_begin = static_cast<int>(std::ceil(l / stride)) * stride;
    const int v_begin = static_cast<int>(std::ceil(t / stride)) * stride;
    long silhouette = 0, inside = 0, visible = 0;
    for (int v = v_begin; v <= b; v += stride) {
      for (int u = u_begin; u <= r; u += stride) {
        const Ray ray(centre, Eigen::Vector3f(static_cast<float>((u - cx) / fx),
                                              static_cast<float>((v - cy) / fy), 1.0f));
        bool hit = false;
        for (int i = 0; i < object.num_primitives && !hit; ++i) {
          hit =
              scene.primitives[object.first_primitive + i].Intersect(ray, 1e-3f, kNoHit) != kNoHit;
        }
        if (!hit) continue;
        ++silhouette;
        if (u < 0 || u >= width || v < 0 || v >= height) continue;
        ++inside;
        if (object_id.at<int>(v, u) == index) ++visible;
      }
    }
    if (silhouette == 0 || inside == 0) continue;
    vis.truncation = 1.0 - static_cast<double>(inside) / silhouette;
    vis.visible_fraction = static_cast<double>(visible) / inside;
    vis.visible_pixels = static_cast<double>(visible) * stride * stride;
    out.push_back(vis);
  }
  return out;
}

LabelSet MakeLabels(const Scene& scene, const Calibration& calib, const cv::Mat& object_id,
                    const LabelOptions& options) {
  const std::vector<ObjectVisibility> seen = MeasureVisibility(scene, calib, object_id, options);
  const double height_scale = object_id.rows / 375.0;
  const double area_scale = height_scale * object_id.cols / 1242.0;
  LabelSet labels, dont_care;
  for (const ObjectVisibility& vis : seen) {
    if (vis.visible_pixels < options.min_visible_pixels * area_scale) continue;
    const SceneObject& so = scene.objects[vis.object];
    const Box2D box{Round2(vis.box.left), Round2(vis.box.top), Round2(vis.box.right),
                    Round2(vis.box.bottom)};
    const double depth = so.box.location.z();
    if (depth > options.max_depth_m || box.Height() < options.min_height_px * height_scale) {
      if (box.Height() < options.min_dontcare_height_px * height_scale) continue;
      Object dc;
      dc.type = "DontCare";
      dc.truncated = -1.0;
      dc.occluded = -1;
      dc.alpha = -10.0;
      dc.box = box;
      dc.box3d.h = dc.box3d.w = dc.box3d.l = -1.0;
      dc.box3d.location = Eigen::Vector3d(-1000.0, -1000.0, -1000.0);
      dc.box3d.rotation_y = -10.0;
      dont_care.labels.push_back(dc);
      dont_care.source.push_back(vis.object);
      continue;
    }
    Object label;
    label.type = so.type;
    label.truncated = Round2(std::clamp(vis.truncation, 0.0, 1.0));
    const double f = vis.visible_fraction;
    label.occluded = f >= options.visible_fraction_occluded_0   ? 0
                     : f >= options.visible_fraction_occluded_1 ? 1
                     : f >= options.visible_fraction_occluded_2 ? 2
                                                                : 3;
    label.box3d = so.box;
    label.alpha = Round2(AlphaFromRotationY(so.box.rotation_y, so.box.location));
    label.box = box;
    labels.labels.push_back(label);
    labels.source.push_back(vis.object);
  }
  labels.labels.insert(labels.labels.end(), dont_care.labels.begin(), dont_care.labels.end());
  labels.source.insert(labels.source.end(), dont_care.source.begin(), dont_care.source.end());
  return labels;
}

}  // namespace stereodet
