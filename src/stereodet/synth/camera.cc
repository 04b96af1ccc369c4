#include "stereodet/synth/camera.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "stereodet/synth/random.h"
#include "stereodet/synth/texture.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {
constexpr int kFullWidth = 1242;
constexpr int kFullHeight = 375;
constexpr int kToneLutSize = 4096;

// Linear radiance in [0, 1] -> 8-bit level (gamma 2.2), as a table: pow() per channel per pixel
// would cost more than the ray cast.
const std::array<float, kToneLutSize + 1>& ToneLut() {
  static const auto lut = [] {
    std::array<float, kToneLutSize + 1> t{};
    for (int i = 0; i <= kToneLutSize; ++i) {
      t[i] = 255.0f * std::pow(static_cast<float>(i) / kToneLutSize, 1.0f / 2.2f);
    }
    return t;
  }();
  return lut;
}

// Approximately standard normal from one 64-bit hash: the sum of four 16-bit uniforms (Irwin-Hall),
// rescaled to unit variance. Plenty for sensor noise, and branch-free.
float HashNormal(uint64_t h) {
  float sum = 0.0f;
  for (int i = 0; i < 4; ++i) {
    sum += static_cast<float>((h >> (16 * i)) & 0xffff) * (1.0f / 65536.0f);
  }
  return (sum - 2.0f) * 1.7320508f;
}
// Screen-space bins of the primitives for one camera: each 16x16 pixel tile lists the primitives
// whose projected bounding box reaches into it, nearest first. A camera ray then tests only its
// tile's list and stops at the first entry that cannot be nearer than the hit it has. For the
// shallow, wide street scenes this costs a few primitive tests per pixel, several times less than
// a BVH traversal (which the LiDAR and the shadow rays still use).
class ScreenBins {
 public:
  ScreenBins(const Scene& scene, const Eigen::Vector3f& centre, float fx, float fy, float cx,
             float cy, int width, int height)
      : tiles_x_((width + kTile - 1) / kTile), tiles_y_((height + kTile - 1) / kTile) {
    constexpr float kNear = 0.01f;
    std::vector<std::array<int, 4>> ranges;  // tile range of each primitive (x0, y0, x1, y1)
    std::vector<float> depths;
    std::vector<int> indices;
    for (int i = 0; i < static_cast<int>(scene.primitives.size()); ++i) {
      const Primitive& p = scene.primitives[i];
      // The oriented box around the primitive (exact for boxes, enclosing for the others).
      std::array<Eigen::Vector3f, 8> corners;
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3f s((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f,
                                (k & 4) ? 1.0f : -1.0f);
        corners[k] = p.centre + p.world_from_local * s.cwiseProduct(p.half_extent) - centre;
      }
      float u0 = kNoHit, u1 = -kNoHit, v0 = kNoHit, v1 = -kNoHit, min_depth = kNoHit;
      const auto add = [&](const Eigen::Vector3f& q) {
        const float u = fx * q.x() / q.z() + cx, v = fy * q.y() / q.z() + cy;
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
      };
      bool any_front = false;
      for (int k = 0; k < 8; ++k) {
        min_depth = std::min(min_depth, corners[k].z());
        if (corners[k].z() >= kNear) {
          add(corners[k]);
          any_front = true;
        }
      }
      if (!any_front) continue;  // wholly behind the camera
      for (int a = 0; a < 8; ++a) {
        if (corners[a].z() >= kNear) continue;
        // The near-plane crossings of segments to the corners in front bound the clipped part.
        for (int b = 0; b < 8; ++b) {
          if (corners[b].z() < kNear) continue;
          const float t = (kNear - corners[a].z()) / (corners[b].z() - corners[a].z());
          add(corners[a] + t * (corners[b] - corners[a]));
        }
      }
      const int px0 = std::max(0, static_cast<int>(std::floor(u0)) - 1);
      const int px1 = std::min(width - 1, static_cast<int>(std::ceil(u1)) + 1);
      const int py0 = std::max(0, static_cast<int>(std::floor(v0)) - 1);
      const int py1 = std::min(height - 1, static_cast<int>(std::ceil(v1)) + 1);
      if (px0 > px1 || py0 > py1) continue;
      ranges.push_back({px0 / kTile, py0 / kTile, px1 / kTile, py1 / kTile});
      depths.push_back(std::max(0.0f, min_depth));
      indices.push_back(i);
    }
    // Compressed rows: count, prefix-sum, fill, then sort each tile's entries by depth.
    offsets_.assign(tiles_x_ * tiles_y_ + 1, 0);
    for (const auto& r : ranges) {
      for (int ty = r[1]; ty <= r[3]; ++ty) {
        for (int tx = r[0]; tx <= r[2]; ++tx) ++offsets_[ty * tiles_x_ + tx + 1];
      }
    }
    for (size_t t = 1; t < offsets_.size(); ++t) offsets_[t] += offsets_[t - 1];
    entries_.resize(offsets_.back());
    std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
    for (size_t k = 0; k < ranges.size(); ++k) {
      const auto& r = ranges[k];
      for (int ty = r[1]; ty <= r[3]; ++ty) {
        for (int tx = r[0]; tx <= r[2]; ++tx)
          entries_[fill[ty * tiles_x_ + tx]++] = {depths[k], indices[k]};
      }
    }
    for (size_t t = 0; t + 1 < offsets_.size(); ++t) {
      std::sort(entries_.begin() + offsets_[t], entries_.begin() + offsets_[t + 1]);
    }
  }

  // Closest primitive hit by the ray of pixel (u, v) with t in (t_min, t_max); the ray's
  // direction must have z = 1 (t is the depth).
  RayHit Intersect(const Scene& scene, const Ray& ray, int u, int v, float t_min,
                   float t_max) const {
    RayHit hit;
    const int tile = (v / kTile) * tiles_x_ + u / kTile;
    for (int k = offsets_[tile]; k < offsets_[tile + 1]; ++k) {
      if (entries_[k].first >= t_max) break;
      const int p = entries_[k].second;
      const float t = scene.primitives[p].Intersect(ray, t_min, t_max);
      if (t < t_max) {
        t_max = t;
        hit = {t, p};
      }
    }
    return hit;
  }

 private:
  static constexpr int kTile = 16;
  int tiles_x_, tiles_y_;
  std::vector<int> offsets_;
  std::vector<std::pair<float, int>> entries_;  // (nearest possible depth, primitive)
};

// The primitives binned as the sun sees them: a grid on the plane perpendicular to the sun
// direction, each cell listing the primitives whose (orthographic) shadow covers it. A shadow ray
// tests only its cell's list, which on street scenes is a handful of primitives.
class SunBins {
 public:
  SunBins(const Scene& scene, const Eigen::Vector3f& to_sun) : to_sun_(to_sun) {
    axis_a_ = to_sun.unitOrthogonal();
    axis_b_ = to_sun.cross(axis_a_);
    struct Extent {
      float a0, a1, b0, b1;
    };
    std::vector<Extent> extents(scene.primitives.size());
    float a_min = kNoHit, a_max = -kNoHit, b_min = kNoHit, b_max = -kNoHit;
    for (size_t i = 0; i < scene.primitives.size(); ++i) {
      const Primitive& p = scene.primitives[i];
      Extent e{kNoHit, -kNoHit, kNoHit, -kNoHit};
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3f s((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f,
                                (k & 4) ? 1.0f : -1.0f);
        const Eigen::Vector3f q = p.centre + p.world_from_local * s.cwiseProduct(p.half_extent);
        const float a = q.dot(axis_a_), b = q.dot(axis_b_);
        e.a0 = std::min(e.a0, a), e.a1 = std::max(e.a1, a), e.b0 = std::min(e.b0, b),
        e.b1 = std::max(e.b1, b);
      }
      extents[i] = e;
      a_min = std::min(a_min, e.a0), a_max = std::max(a_max, e.a1);
      b_min = std::min(b_min, e.b0), b_max = std::max(b_max, e.b1);
    }
    if (extents.empty()) return;
    origin_a_ = a_min;
    origin_b_ = b_min;
    // About 1 m cells, at most 512 x 512 of them.
    cell_ = std::max({1.0f, (a_max - a_min) / 512.0f, (b_max - b_min) / 512.0f});
    cells_a_ = static_cast<int>((a_max - a_min) / cell_) + 1;
    cells_b_ = static_cast<int>((b_max - b_min) / cell_) + 1;
    offsets_.assign(static_cast<size_t>(cells_a_) * cells_b_ + 1, 0);
    const auto range = [&](const Extent& e) {
      return std::array<int, 4>{Cell(e.a0, origin_a_, cells_a_), Cell(e.b0, origin_b_, cells_b_),
                                Cell(e.a1, origin_a_, cells_a_), Cell(e.b1, origin_b_, cells_b_)};
    };
    for (const Extent& e : extents) {
      const auto r = range(e);
      for (int j = r[1]; j <= r[3]; ++j) {
        for (int i = r[0]; i <= r[2]; ++i) ++offsets_[static_cast<size_t>(j) * cells_a_ + i + 1];
      }
    }
    for (size_t k = 1; k < offsets_.size(); ++k) offsets_[k] += offsets_[k - 1];
    entries_.resize(offsets_.back());
    std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
    for (size_t p = 0; p < extents.size(); ++p) {
      const auto r = range(extents[p]);
      for (int j = r[1]; j <= r[3]; ++j) {
        for (int i = r[0]; i <= r[2]; ++i)
          entries_[fill[static_cast<size_t>(j) * cells_a_ + i]++] = static_cast<int>(p);
      }
    }
  }

  // Whether a primitive blocks the ray from `point` towards the sun within `max_distance`.
  // `hint` as in Scene::Occluded.
  bool Occluded(const Scene& scene, const Eigen::Vector3f& point, float max_distance,
                int* hint) const {
    if (entries_.empty()) return false;
    const Ray ray(point, to_sun_);
    if (*hint >= 0 && scene.primitives[*hint].Intersect(ray, 0.0f, max_distance) != kNoHit)
      return true;
    const int i = Cell(point.dot(axis_a_), origin_a_, cells_a_);
    const int j = Cell(point.dot(axis_b_), origin_b_, cells_b_);
    const size_t cell = static_cast<size_t>(j) * cells_a_ + i;
    for (int k = offsets_[cell]; k < offsets_[cell + 1]; ++k) {
      const int p = entries_[k];
      if (p == *hint) continue;
      if (scene.primitives[p].Intersect(ray, 0.0f, max_distance) != kNoHit) {
        *hint = p;
        return true;
      }
    }
    return false;
  }

 private:
  // Clamped: points outside the grid fall into its border cells, which is conservative only if
  // no primitive lies beyond them, and none does (the grid covers every primitive).
  int Cell(float x, float origin, int cells) const {
    return std::clamp(static_cast<int>((x - origin) / cell_), 0, cells - 1);
  }

  Eigen::Vector3f to_sun_, axis_a_, axis_b_;
  float origin_a_ = 0.0f, origin_b_ = 0.0f, cell_ = 1.0f;
  int cells_a_ = 0, cells_b_ = 0;
  std::vector<int> offsets_;
  std::vector<int> entries_;
};

}  // namespace

Calibration SynthCalibration(int width, int height) {
  STEREODET_CHECK(width >= 8 && height >= 8)
      << "image size must be at least 8x8, got " << width << "x" << height;
  Calibration calib = KittiLikeCalibration();
  const double sx = static_cast<double>(width) / kFullWidth;
  const double sy = static_cast<double>(height) / kFullHeight;
  for (Matrix34d& p : calib.projection) {
    const Eigen::Matrix3d k = p.leftCols<3>();
    const Eigen::Vector3d t = k.inverse() * p.col(3);  // metres; kept
    Eigen::Matrix3d scaled = Eigen::Matrix3d::Identity();
    // Pixel centres at integers: a pixel-centre coordinate x maps to (x + 0.5) s - 0.5.
    scaled(0, 0) = scaled(1, 1) = k(0, 0) * sx;
    scaled(0, 2) = (k(0, 2) + 0.5) * sx - 0.5;
    scaled(1, 2) = (k(1, 2) + 0.5) * sy - 0.5;
    p.leftCols<3>() = scaled;
    p.col(3) = scaled * t;
  }
  return calib;
}

void RenderOptions::Check() const {
  STEREODET_CHECK(optics_blur_sigma_px >= 0.0f && optics_blur_sigma_px <= 5.0f)
      << "optics_blur_sigma_px must be in [0, 5], got " << optics_blur_sigma_px;
  STEREODET_CHECK(vignetting >= 0.0f && vignetting < 1.0f)
      << "vignetting must be in [0, 1), got " << vignetting;
  STEREODET_CHECK(noise_sigma >= 0.0f && noise_sigma <= 50.0f)
      << "noise_sigma must be in [0, 50], got " << noise_sigma;
  STEREODET_CHECK(max_depth_m > 0.0f) << "max_depth_m must be positive, got " << max_depth_m;
}

void GroundTruthDisparityOptions::Check() const {
  STEREODET_CHECK(depth_tolerance_rel >= 0.0f && depth_tolerance_abs_m >= 0.0f)
      << "depth tolerances must be non-negative";
}

CameraRender RenderCamera(const Scene& scene, const Calibration& calib,
                          const RenderRequest& request, const RenderOptions& options) {
  options.Check();
  STEREODET_CHECK(request.camera >= 0 && request.camera < 4)
      << "camera must be 0..3, got " << request.camera;
  STEREODET_CHECK(request.width >= 1 && request.height >= 1)
      << "image size must be positive, got " << request.width << "x" << request.height;
  const int width = request.width, height = request.height;
  const Matrix34d& p = calib.projection[request.camera];
  const float fx = static_cast<float>(p(0, 0)), fy = static_cast<float>(p(1, 1));
  const float cx = static_cast<float>(p(0, 2)), cy = static_cast<float>(p(1, 2));
  STEREODET_CHECK(fx > 0 && fy > 0 && p(0, 1) == 0.0 && p(2, 0) == 0.0 && p(2, 1) == 0.0 &&
                  p(2, 2) == 1.0)
      << "RenderCamera needs a rectified projection K [I | t] with zero skew";
  const Eigen::Vector3f centre = calib.CameraCentreInRect(request.camera).cast<float>();
  const float pixel_angle = 1.0f / fx;  // radians per pixel at the image centre

  CameraRender out;
  cv::Mat radiance(height, width, CV_32FC3);
  out.depth.create(height, width, CV_32FC1);
  if (request.object_ids) out.object_id.create(height, width, CV_32SC1);
  if (request.points) out.points.create(height, width, CV_32FC3);
  const Lighting& light = scene.light;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float half_diag_sq =
      0.25f * (static_cast<float>(width) * width + static_cast<float>(height) * height);

  const ScreenBins bins(scene, centre, fx, fy, cx, cy, width, height);
  std::optional<SunBins> sun_bins;
  if (options.shadows) sun_bins.emplace(scene, scene.light.to_sun);
  // Coherence hint: the primitive that shadowed the previous pixel.
  int shadow_hint = -1;
  for (int v = 0; v < height; ++v) {
    auto* rad_row = radiance.ptr<cv::Vec3f>(v);
    auto* depth_row = out.depth.ptr<float>(v);
    int* id_row = request.object_ids ? out.object_id.ptr<int>(v) : nullptr;
    auto* point_row = request.points ? out.points.ptr<cv::Vec3f>(v) : nullptr;
    const float dy = (v - cy) / fy;
    for (int u = 0; u < width; ++u) {
      // Direction with z = 1: the ray parameter is the depth in front of this camera.
      const Eigen::Vector3f dir((u - cx) / fx, dy, 1.0f);
      const Ray ray(centre, dir);
      const float ground_t = scene.GroundHit(ray, 1e-3f, kNoHit);
      const RayHit prim_hit = bins.Intersect(scene, ray, u, v, 1e-3f, ground_t);
      const SurfaceHit hit = prim_hit.primitive >= 0
                                 ? scene.MakeHit(ray, prim_hit.t, prim_hit.primitive)
                                 : scene.MakeHit(ray, ground_t, -1);
      const float dir_norm = dir.norm();
      const Eigen::Vector3f dir_unit = dir / dir_norm;
      Eigen::Vector3f color;
      const bool valid = hit.Hit() && hit.t <= options.max_depth_m;
      if (!hit.Hit()) {
        color = SkyRadiance(light, dir_unit);
      } else {
        const float distance = hit.t * dir_norm;
        const float cos_view = std::abs(hit.normal.dot(dir_unit));
        // Texture filter width. On horizontal surfaces (the road, sidewalks) a pixel row holds
        // points of one depth in both cameras (rectified rows), so detail finer than the row
        // spacing along the depth is sampled alike by both and only the across-row spacing
        // (distance x pixel angle) has to be respected; elsewhere the footprint widens with the
        // obliquity.
        const float footprint = std::abs(hit.normal.y()) > 0.9f
                                    ? distance * pixel_angle
                                    : distance * pixel_angle / std::sqrt(std::max(cos_view, 0.05f));
        const Eigen::Vector3f albedo = SurfaceAlbedo(scene, hit, footprint);
        const float up = -hit.normal.y();
        Eigen::Vector3f irradiance = light.sky_ambient * (0.6f + 0.4f * up);
        const float sun_cos = hit.normal.dot(light.to_sun);
        bool lit = false;
        if (sun_cos > 0.0f) {
          lit = true;
          if (options.shadows) {
            lit = !sun_bins->Occluded(scene, hit.point + 0.005f * hit.normal,
                                      options.shadow_distance_m, &shadow_hint);
          }
          if (lit) irradiance += sun_cos * light.sun;
        }
        color = albedo.cwiseProduct(irradiance);
        const float specular = scene.materials[hit.material].specular;
        if (specular > 0.0f) {
          // Mirror the street and the sky, more at grazing angles (a cheap Fresnel term) ...
          const Eigen::Vector3f reflected = dir_unit - 2.0f * dir_unit.dot(hit.normal) * hit.normal;
          const float grazing = 1.0f - cos_view;
          const float fresnel = specular * (0.3f + 0.7f * grazing * grazing * grazing);
          color += fresnel * ReflectedRadiance(light, reflected);
          // ... and the sun's glint on the clear coat (view-dependent, as real highlights).
          if (lit) {
            const float r = std::max(0.0f, reflected.dot(light.to_sun));
            const float r2 = r * r, r4 = r2 * r2, r8 = r4 * r4, r16 = r8 * r8;
            color += (1.5f * specular * r16 * r16 * r16) * light.sun;  // lobe r^48
          }
        }
        const float haze = 1.0f - std::exp(-distance * light.haze_per_m);
        color += haze * (light.sky_horizon - color);
      }
      const float du = u - cx, dv = v - cy;
      const float vignette = 1.0f - options.vignetting * (du * du + dv * dv) / half_diag_sq;
      color = color.cwiseProduct(light.white_balance) * (light.exposure * request.gain * vignette);
      rad_row[u] = cv::Vec3f(color.z(), color.y(), color.x());  // BGR
      depth_row[u] = valid ? hit.t : 0.0f;
      if (id_row != nullptr) id_row[u] = valid ? hit.object : -1;
      if (point_row != nullptr) {
        point_row[u] = valid ? cv::Vec3f(hit.point.x(), hit.point.y(), hit.point.z())
                             : cv::Vec3f(nan, nan, nan);
      }
    }
  }
  if (options.optics_blur_sigma_px > 0.0f) {
    cv::GaussianBlur(radiance, radiance, cv::Size(0, 0), options.optics_blur_sigma_px);
  }
  const auto& lut = ToneLut();
  const float noise_sigma = options.noise_sigma * scene.light.noise_scale;
  out.image.create(height, width, CV_8UC3);
  const uint64_t camera_seed = HashOf({request.noise_seed, static_cast<uint64_t>(request.camera)});
  for (int v = 0; v < height; ++v) {
    const auto* rad_row = radiance.ptr<cv::Vec3f>(v);
    auto* img_row = out.image.ptr<cv::Vec3b>(v);
    for (int u = 0; u < width; ++u) {
      const uint64_t pixel_hash = Mix64(camera_seed ^ (static_cast<uint64_t>(v) * width + u));
      for (int c = 0; c < 3; ++c) {
        const float x = std::clamp(rad_row[u][c], 0.0f, 1.0f);
        float level = lut[static_cast<int>(x * kToneLutSize + 0.5f)];
        level += noise_sigma * HashNormal(Mix64(pixel_hash + c));
        img_row[u][c] = cv::saturate_cast<uchar>(level);
      }
    }
  }
  return out;
}

cv::Mat GroundTruthDisparity(const Calibration& calib, const CameraRender& left,
                             const CameraRender& right,
                             const GroundTruthDisparityOptions& options) {
  options.Check();
  STEREODET_CHECK(!left.points.empty() && left.points.type() == CV_32FC3)
      << "GroundTruthDisparity needs the left render's points";
  STEREODET_CHECK(!right.depth.empty() && right.depth.type() == CV_32FC1)
      << "GroundTruthDisparity needs the right render's depth";
  const Matrix34d& p2 = calib.projection[2];
  const Matrix34d& p3 = calib.projection[3];
  const int rows = right.depth.rows, cols = right.depth.cols;
  cv::Mat disparity(left.points.size(), CV_32FC1, cv::Scalar(0.0f));
  for (int v = 0; v < left.points.rows; ++v) {
    const auto* pts = left.points.ptr<cv::Vec3f>(v);
    auto* out = disparity.ptr<float>(v);
    for (int u = 0; u < left.points.cols; ++u) {
      if (std::isnan(pts[u][0])) continue;
      const Eigen::Vector4d x(pts[u][0], pts[u][1], pts[u][2], 1.0);
      const Eigen::Vector3d h2 = p2 * x, h3 = p3 * x;
      if (h2.z() <= 0.0 || h3.z() <= 0.0) continue;
      const double u2 = h2.x() / h2.z(), u3 = h3.x() / h3.z(), v3 = h3.y() / h3.z();
      const int row = static_cast<int>(std::lround(v3));
      if (row < 0 || row >= rows) continue;
      const int c0 = static_cast<int>(std::floor(u3));
      const float z3 = static_cast<float>(h3.z());
      const float tolerance = options.depth_tolerance_rel * z3 + options.depth_tolerance_abs_m;
      bool visible = false;
      for (int c = c0; c <= c0 + 1 && !visible; ++c) {
        if (c < 0 || c >= cols) continue;
        const float zb = right.depth.at<float>(row, c);
        visible = zb > 0.0f && std::abs(zb - z3) <= tolerance;
      }
      if (visible) out[u] = static_cast<float>(u2 - u3);
    }
  }
  return disparity;
}

cv::Mat EncodeKittiDisparity(const cv::Mat& disparity_px) {
  STEREODET_CHECK(disparity_px.type() == CV_32FC1) << "disparity must be CV_32FC1";
  cv::Mat encoded(disparity_px.size(), CV_16UC1, cv::Scalar(0));
  for (int v = 0; v < disparity_px.rows; ++v) {
    const float* in = disparity_px.ptr<float>(v);
    auto* out = encoded.ptr<uint16_t>(v);
    for (int u = 0; u < disparity_px.cols; ++u) {
      if (!(in[u] > 0.0f)) continue;
      const long value = std::lround(static_cast<double>(in[u]) * 256.0);
      out[u] = static_cast<uint16_t>(std::clamp<long>(value, 1, 65535));
    }
  }
  return encoded;
}

cv::Mat DecodeKittiDisparity(const cv::Mat& encoded) {
  STEREODET_CHECK(encoded.type() == CV_16UC1) << "KITTI disparity must be CV_16UC1";
  cv::Mat disparity;
  encoded.convertTo(disparity, CV_32FC1, 1.0 / 256.0);
  return disparity;
}

}  // namespace stereodet
