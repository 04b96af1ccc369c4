#include "stereodet/synth/lidar.h"

#include <algorithm>
#include <cmath>

#include "stereodet/synth/random.h"
#include "stereodet/synth/texture.h"
#include "stereodet/util/check.h"

namespace stereodet {

void LidarOptions::Check() const {
  STEREODET_CHECK(azimuth_step_deg > 0.0 && azimuth_step_deg <= 5.0)
      << "azimuth_step_deg must be in (0, 5], got " << azimuth_step_deg;
  STEREODET_CHECK(max_range_m > min_range_m && min_range_m >= 0.0)
      << "need 0 <= min_range_m < max_range_m, got " << min_range_m << ", " << max_range_m;
  STEREODET_CHECK(range_noise_m >= 0.0 && range_noise_m < 1.0)
      << "range_noise_m must be in [0, 1), got " << range_noise_m;
  STEREODET_CHECK(dropout >= 0.0 && dropout < 1.0) << "dropout must be in [0, 1), got " << dropout;
  STEREODET_CHECK(reflectance_noise >= 0.0) << "reflectance_noise must be >= 0";
}

std::vector<double> Hdl64ElevationsDeg() {
  std::vector<double> elevations(64);
  for (int i = 0; i < 32; ++i) elevations[i] = 2.0 + (-8.33 - 2.0) * i / 31.0;
  for (int i = 0; i < 32; ++i) elevations[32 + i] = -8.83 + (-24.9 + 8.83) * i / 31.0;
  return elevations;
}

std::vector<VeloPoint> SimulateLidar(const Scene& scene, const Calibration& calib,
                                     const LidarOptions& options, uint64_t seed) {
  options.Check();
  const Eigen::Affine3d rect_from_velo = calib.RectFromVelo();
  const Eigen::Affine3d velo_from_rect = rect_from_velo.inverse();
  const Eigen::Matrix3f rect_from_velo_rot = rect_from_velo.linear().cast<float>();
  const Eigen::Vector3f origin = rect_from_velo.translation().cast<float>();
  const int columns = static_cast<int>(std::lround(360.0 / options.azimuth_step_deg));
  const std::vector<double> elevations = Hdl64ElevationsDeg();

  // Precomputed azimuth sines and cosines, shared by all beams.
  std::vector<float> cos_az(columns), sin_az(columns);
  for (int c = 0; c < columns; ++c) {
    const double az = (-180.0 + c * options.azimuth_step_deg) * M_PI / 180.0;
    cos_az[c] = static_cast<float>(std::cos(az));
    sin_az[c] = static_cast<float>(std::sin(az));
  }
  Rng rng(seed);
  std::vector<VeloPoint> points;
  points.reserve(static_cast<size_t>(columns) * elevations.size());
  const float max_range = static_cast<float>(options.max_range_m);
  for (double elevation_deg : elevations) {
    const float ce = static_cast<float>(std::cos(elevation_deg * M_PI / 180.0));
    const float se = static_cast<float>(std::sin(elevation_deg * M_PI / 180.0));
    for (int c = 0; c < columns; ++c) {
      const Eigen::Vector3f dir_velo(ce * cos_az[c], ce * sin_az[c], se);
      const Eigen::Vector3f dir = rect_from_velo_rot * dir_velo;  // unit: t is the range
      const SurfaceHit hit = scene.Trace(Ray(origin, dir), 1e-3f, max_range);
      if (!hit.Hit() || hit.t < options.min_range_m) continue;
      // Noise is drawn for returns only (the sky costs nothing); still a pure function of the seed
      // and the scene.
      const double range_error = rng.Normal(0.0, options.range_noise_m);
      const double drop_draw = rng.Uniform();
      const double reflect_error = rng.Normal(0.0, options.reflectance_noise);
      const Material& material = scene.materials[hit.material];
      float reflectance = material.lidar_reflectance;
      if (hit.kind == SurfaceHit::Kind::kGround && hit.material == scene.road_material &&
          OnRoadMarking(scene.road, hit.point.x(), hit.point.z())) {
        reflectance = 0.75f;  // retro-reflective paint
      }
      const float cos_incidence = std::abs(hit.normal.dot(dir));
      reflectance *= 0.35f + 0.65f * cos_incidence;
      double drop = options.dropout;
      if (reflectance < 0.05f && hit.t > options.dark_dropout_range_m) drop = std::max(drop, 0.5);
      if (drop_draw < drop) continue;
      const double range = hit.t + range_error;
      const Eigen::Vector3d point_rect = origin.cast<double>() + range * dir.cast<double>();
      const Eigen::Vector3d point_velo = velo_from_rect * point_rect;
      const double intensity = std::clamp(reflectance + reflect_error, 0.0, 1.0);
      VeloPoint p;
      p.x = static_cast<float>(point_velo.x());
      p.y = static_cast<float>(point_velo.y());
      p.z = static_cast<float>(point_velo.z());
      p.reflectance = static_cast<float>(std::round(intensity * 100.0) / 100.0);
      points.push_back(p);
    }
  }
  return points;
}

}  // namespace stereodet
