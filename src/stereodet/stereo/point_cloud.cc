#include "stereodet/stereo/point_cloud.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "stereodet/stereo/disparity.h"
#include "stereodet/util/check.h"

namespace stereodet {

void PointCloudOptions::Check() const {
  STEREODET_CHECK(std::isfinite(max_depth_m) && max_depth_m > 0)
      << "point cloud max_depth_m must be a finite number > 0, got " << max_depth_m;
  STEREODET_CHECK(min_height_m < max_height_m)
      << "point cloud height range is empty: [" << min_height_m << ", " << max_height_m << "]";
  STEREODET_CHECK(beams >= 0) << "point cloud beams must be >= 0, got " << beams;
  if (beams > 0) {
    STEREODET_CHECK(min_elevation_deg < max_elevation_deg && min_elevation_deg > -90 &&
                    max_elevation_deg < 90)
        << "beam elevations must satisfy -90 < min < max < 90";
    STEREODET_CHECK(azimuth_step_deg > 0) << "azimuth_step_deg must be > 0 with beams";
  }
}

std::vector<VeloPoint> StereoPointCloud(const cv::Mat& disparity_px, const cv::Mat& left_grey,
                                        const StereoGeometry& geometry, const GroundPlane& ground,
                                        const PointCloudOptions& options) {
  options.Check();
  STEREODET_CHECK(disparity_px.type() == CV_32FC1) << "disparity must be CV_32FC1";
  STEREODET_CHECK(left_grey.type() == CV_8UC1 && left_grey.size() == disparity_px.size())
      << "left grey image must be CV_8UC1 of the disparity's size";
  std::vector<VeloPoint> points;
  for (int v = 0; v < disparity_px.rows; ++v) {
    const float* d = disparity_px.ptr<float>(v);
    const uint8_t* grey = left_grey.ptr<uint8_t>(v);
    for (int u = 0; u < disparity_px.cols; ++u) {
      if (!IsValidDisparity(d[u])) continue;
      if (geometry.DepthFromDisparity(d[u]) > options.max_depth_m) continue;
      const Eigen::Vector3d in_rect = geometry.PointInRect(u, v, d[u]);
      const double height = ground.HeightAbove(in_rect);
      if (height < options.min_height_m || height > options.max_height_m) continue;
      const Eigen::Vector3d in_velo = geometry.velo_from_rect * in_rect;
      points.push_back({static_cast<float>(in_velo.x()), static_cast<float>(in_velo.y()),
                        static_cast<float>(in_velo.z()), ReflectanceFromGrey(grey[u])});
    }
  }
  return SubsampleToBeams(points, options);
}

std::vector<VeloPoint> SubsampleToBeams(const std::vector<VeloPoint>& points,
                                        const PointCloudOptions& options) {
  options.Check();
  if (options.beams == 0) return points;
  const double spacing_deg =
      options.beams > 1
          ? (options.max_elevation_deg - options.min_elevation_deg) / (options.beams - 1)
          : 1.0;
  // Bin (beam, azimuth) -> index of the point nearest the beam's elevation so far.
  struct Best {
    size_t index;
    double distance_deg;
  };
  std::unordered_map<long long, Best> best;
  for (size_t i = 0; i < points.size(); ++i) {
    const VeloPoint& p = points[i];
    const double elevation_deg = std::atan2(p.z, std::hypot(p.x, p.y)) * 180.0 / M_PI;
    const long beam = std::lround((elevation_deg - options.min_elevation_deg) / spacing_deg);
    if (beam < 0 || beam >= options.beams) continue;
    const double distance_deg =
        std::abs(elevation_deg - (options.min_elevation_deg + beam * spacing_deg));
    if (distance_deg > 0.5 * spacing_deg) continue;
    const double azimuth_deg = std::atan2(p.y, p.x) * 180.0 / M_PI;
    const long long azimuth_bin =
        static_cast<long long>(std::floor((azimuth_deg + 180.0) / options.azimuth_step_deg));
    const long long key = beam * 1000000LL + azimuth_bin;
    auto [it, inserted] = best.try_emplace(key, Best{i, distance_deg});
    if (!inserted && distance_deg < it->second.distance_deg) it->second = Best{i, distance_deg};
  }
  std::vector<size_t> keep;
  keep.reserve(best.size());
  for (const auto& [key, entry] : best) keep.push_back(entry.index);
  std::sort(keep.begin(), keep.end());
  std::vector<VeloPoint> out;
  out.reserve(keep.size());
  for (size_t index : keep) out.push_back(points[index]);
  return out;
}

}  // namespace stereodet
