#include "stereodet/stereo/stereo_encoder.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <type_traits>

#include "stereodet/stereo/rgbh.h"
#include "stereodet/util/check.h"

namespace stereodet {

void StereoOptions::Check() const {
  disparity.Check();
  ground.Check();
  height.Check();
  depth.Check();
  points.Check();
  blur.Check();
}

namespace {

nlohmann::json SettingsJson(const StereoOptions& o) {
  const DisparityOptions& d = o.disparity;
  nlohmann::json j;
  j["disparity"] = {{"method", DisparityMethodName(d.method)},
                    {"num_disparities", d.num_disparities},
                    {"min_disparity", d.min_disparity},
                    {"uniqueness_ratio", d.uniqueness_ratio},
                    {"speckle_window_px", d.speckle_window_px},
                    {"speckle_range_px", d.speckle_range_px},
                    {"left_right_max_diff_px", d.left_right_max_diff_px},
                    {"bm_block_size", d.bm.block_size},
                    {"bm_xsobel_prefilter", d.bm.xsobel_prefilter},
                    {"bm_prefilter_size", d.bm.prefilter_size},
                    {"bm_prefilter_cap", d.bm.prefilter_cap},
                    {"bm_texture_threshold", d.bm.texture_threshold},
                    {"sgbm_block_size", d.sgbm.block_size},
                    {"sgbm_p1_per_pixel", d.sgbm.p1_per_pixel},
                    {"sgbm_p2_per_pixel", d.sgbm.p2_per_pixel},
                    {"sgbm_p1", d.sgbm.p1 ? nlohmann::json(*d.sgbm.p1) : nlohmann::json()},
                    {"sgbm_p2", d.sgbm.p2 ? nlohmann::json(*d.sgbm.p2) : nlohmann::json()},
                    {"sgbm_prefilter_cap", d.sgbm.prefilter_cap},
                    {"sgbm_mode", SgbmModeName(d.sgbm.mode)},
                    {"sgbm_colour", d.sgbm.colour},
                    {"wls_enabled", d.wls.enabled},
                    {"wls_lambda", d.wls.lambda},
                    {"wls_sigma_color", d.wls.sigma_color},
                    {"wls_lrc_threshold", d.wls.lrc_threshold},
                    {"wls_depth_discontinuity_radius", d.wls.depth_discontinuity_radius},
                    {"match_scale", d.match_scale}};
  const GroundPlaneOptions& g = o.ground;
  j["ground"] = {{"enabled", g.enabled},
                 {"nominal_camera_height_m", g.nominal_camera_height_m},
                 {"roi_fraction", g.roi_fraction},
                 {"sample_step_px", g.sample_step_px},
                 {"min_depth_m", g.min_depth_m},
                 {"max_depth_m", g.max_depth_m},
                 {"max_lateral_m", g.max_lateral_m},
                 {"max_samples", g.max_samples},
                 {"iterations", g.iterations},
                 {"inlier_threshold_m", g.inlier_threshold_m},
                 {"seed", g.seed},
                 {"min_inliers", g.min_inliers},
                 {"min_inlier_fraction", g.min_inlier_fraction},
                 {"max_tilt_deg", g.max_tilt_deg},
                 {"min_camera_height_m", g.min_camera_height_m},
                 {"max_camera_height_m", g.max_camera_height_m},
                 {"suspect_uses_prior", g.suspect_uses_prior}};
  j["height_code"] = {
      {"min_m", o.height.min_m}, {"max_m", o.height.max_m}, {"levels", 511}, {"no_stereo", 0}};
  return j;
}

// Reads `section`.`key` of `j` into `field` when present.
template <typename T>
void Read(const nlohmann::json& j, const char* section, const char* key, const std::string& source,
          T& field) {
  if (!j.contains(section) || !j[section].is_object() || !j[section].contains(key)) return;
  const nlohmann::json& value = j[section][key];
  try {
    if constexpr (std::is_same_v<T, std::optional<int>>) {
      field = value.is_null() ? std::nullopt : std::optional<int>(value.get<int>());
    } else {
      field = value.get<T>();
    }
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, std::string(section) + "." + key, e.what());
  }
}

}  // namespace

std::string StereoSettingsJson(const StereoOptions& options) {
  return SettingsJson(options).dump(2) + "\n";
}

StereoOptions StereoOptionsFromJson(const std::string& text, const std::string& source,
                                    const StereoOptions& defaults) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw ParseError(source, 0, "", std::string("not valid JSON: ") + e.what());
  }
  StereoOptions o = defaults;
  DisparityOptions& d = o.disparity;
  std::string method = DisparityMethodName(d.method), mode = SgbmModeName(d.sgbm.mode);
  Read(j, "disparity", "method", source, method);
  const auto parsed_method = ParseDisparityMethod(method);
  if (!parsed_method) throw ParseError(source, 0, "disparity.method", "unknown '" + method + "'");
  d.method = *parsed_method;
  Read(j, "disparity", "num_disparities", source, d.num_disparities);
  Read(j, "disparity", "min_disparity", source, d.min_disparity);
  Read(j, "disparity", "uniqueness_ratio", source, d.uniqueness_ratio);
  Read(j, "disparity", "speckle_window_px", source, d.speckle_window_px);
  Read(j, "disparity", "speckle_range_px", source, d.speckle_range_px);
  Read(j, "disparity", "left_right_max_diff_px", source, d.left_right_max_diff_px);
  Read(j, "disparity", "bm_block_size", source, d.bm.block_size);
  Read(j, "disparity", "bm_xsobel_prefilter", source, d.bm.xsobel_prefilter);
  Read(j, "disparity", "bm_prefilter_size", source, d.bm.prefilter_size);
  Read(j, "disparity", "bm_prefilter_cap", source, d.bm.prefilter_cap);
  Read(j, "disparity", "bm_texture_threshold", source, d.bm.texture_threshold);
  Read(j, "disparity", "sgbm_block_size", source, d.sgbm.block_size);
  Read(j, "disparity", "sgbm_p1_per_pixel", source, d.sgbm.p1_per_pixel);
  Read(j, "disparity", "sgbm_p2_per_pixel", source, d.sgbm.p2_per_pixel);
  Read(j, "disparity", "sgbm_p1", source, d.sgbm.p1);
  Read(j, "disparity", "sgbm_p2", source, d.sgbm.p2);
  Read(j, "disparity", "sgbm_prefilter_cap", source, d.sgbm.prefilter_cap);
  Read(j, "disparity", "sgbm_mode", source, mode);
  const auto parsed_mode = ParseSgbmMode(mode);
  if (!parsed_mode) throw ParseError(source, 0, "disparity.sgbm_mode", "unknown '" + mode + "'");
  d.sgbm.mode = *parsed_mode;
  Read(j, "disparity", "sgbm_colour", source, d.sgbm.colour);
  Read(j, "disparity", "wls_enabled", source, d.wls.enabled);
  Read(j, "disparity", "wls_lambda", source, d.wls.lambda);
  Read(j, "disparity", "wls_sigma_color", source, d.wls.sigma_color);
  Read(j, "disparity", "wls_lrc_threshold", source, d.wls.lrc_threshold);
  Read(j, "disparity", "wls_depth_discontinuity_radius", source, d.wls.depth_discontinuity_radius);
  Read(j, "disparity", "match_scale", source, d.match_scale);
  GroundPlaneOptions& g = o.ground;
  Read(j, "ground", "enabled", source, g.enabled);
  Read(j, "ground", "nominal_camera_height_m", source, g.nominal_camera_height_m);
  Read(j, "ground", "roi_fraction", source, g.roi_fraction);
  Read(j, "ground", "sample_step_px", source, g.sample_step_px);
  Read(j, "ground", "min_depth_m", source, g.min_depth_m);
  Read(j, "ground", "max_depth_m", source, g.max_depth_m);
  Read(j, "ground", "max_lateral_m", source, g.max_lateral_m);
  Read(j, "ground", "max_samples", source, g.max_samples);
  Read(j, "ground", "iterations", source, g.iterations);
  Read(j, "ground", "inlier_threshold_m", source, g.inlier_threshold_m);
  Read(j, "ground", "seed", source, g.seed);
  Read(j, "ground", "min_inliers", source, g.min_inliers);
  Read(j, "ground", "min_inlier_fraction", source, g.min_inlier_fraction);
  Read(j, "ground", "max_tilt_deg", source, g.max_tilt_deg);
  Read(j, "ground", "min_camera_height_m", source, g.min_camera_height_m);
  Read(j, "ground", "max_camera_height_m", source, g.max_camera_height_m);
  Read(j, "ground", "suspect_uses_prior", source, g.suspect_uses_prior);
  Read(j, "height_code", "min_m", source, o.height.min_m);
  Read(j, "height_code", "max_m", source, o.height.max_m);
  try {
    o.Check();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(source + ": " + e.what());
  }
  return o;
}

std::string DifferingStereoSettings(const StereoOptions& recorded, const StereoOptions& requested) {
  const nlohmann::json a = SettingsJson(recorded), b = SettingsJson(requested);
  std::string differences;
  for (const auto& [section, values] : b.items()) {
    for (const auto& [key, value] : values.items()) {
      const nlohmann::json& old_value = a[section][key];
      if (old_value == value) continue;
      if (!differences.empty()) differences += "; ";
      differences +=
          section + "." + key + ": " + old_value.dump() + " (requested: " + value.dump() + ")";
    }
  }
  return differences;
}

StereoEncoder::StereoEncoder(const StereoOptions& options)
    : options_(options), match_ground_(options.ground), matcher_(options.disparity) {
  options_.Check();
  if (options_.disparity.match_scale < 1.0) {
    match_ground_.sample_step_px =
        std::max(1, static_cast<int>(std::lround(options_.ground.sample_step_px *
                                                 options_.disparity.match_scale)));
  }
}

StereoEncoding StereoEncoder::Encode(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                                     const StereoGeometry& geometry, const StereoOutputs& outputs,
                                     StageTimes* times) {
  STEREODET_CHECK(left_bgr.type() == CV_8UC3 && right_bgr.type() == CV_8UC3)
      << "stereo encoding needs 8-bit BGR images, got types " << left_bgr.type() << " and "
      << right_bgr.type();
  STEREODET_CHECK(left_bgr.size() == right_bgr.size()) << "left and right images differ in size";
  Timer timer;
  auto stage = [&](const char* name) {
    if (times != nullptr) times->Add(name, timer.ElapsedSeconds());
    timer.Restart();
  };
  cv::Mat network_image = left_bgr;
  cv::Mat match_left = left_bgr, match_right = right_bgr;
  if (options_.blur.sigma_px > 0) {
    network_image = GaussianBlurImage(left_bgr, options_.blur.sigma_px);
    if (options_.blur.mode == BlurMode::kBothBeforeMatching) {
      match_left = network_image;
      match_right = GaussianBlurImage(right_bgr, options_.blur.sigma_px);
    }
    stage("blur");
  }
  // At match_scale < 1 the grey pair (the colour pair for SGBM on colour, and the WLS guide) is
  // resized to the match size; grey first, so the resize reads one channel.
  const cv::Size full_size = left_bgr.size();
  const cv::Size match_size = options_.disparity.MatchSize(full_size);
  const bool scaled = match_size != full_size;
  const cv::Mat left_grey = ResizeForMatching(ToGrey(match_left), match_size);
  const bool colour = options_.disparity.MatchesColour();
  const cv::Mat right_grey =
      colour ? cv::Mat() : ResizeForMatching(ToGrey(match_right), match_size);
  const cv::Mat guide = options_.disparity.wls.enabled || colour
                            ? ResizeForMatching(match_left, match_size)
                            : cv::Mat();
  const cv::Mat colour_right = colour ? ResizeForMatching(match_right, match_size) : cv::Mat();
  stage("grey");
  // SGBM on colour reads the BGR pair as OpenCV takes it; the WLS filter is guided by the left
  // colour image either way.
  const cv::Mat fixed_point = colour ? matcher_.ComputeFixedPoint(guide, colour_right, guide)
                                     : matcher_.ComputeFixedPoint(left_grey, right_grey, guide);
  stage("disparity");
  if (!scaled) {
    return EncodeFromFixedPoint(fixed_point, network_image, left_grey, geometry, outputs, times);
  }
  STEREODET_CHECK(outputs.full_resolution || !outputs.rgbh)
      << "an RGB-H image needs the full-resolution outputs (match_scale "
      << options_.disparity.match_scale << ")";
  StereoOutputs at_match_scale = outputs;
  at_match_scale.rgbh = false;  // packed below, at the network image's size
  const StereoGeometry match_geometry =
      geometry.Scaled(static_cast<double>(match_size.width) / full_size.width,
                      static_cast<double>(match_size.height) / full_size.height);
  StereoEncoding encoding = EncodeFromFixedPoint(fixed_point, network_image, left_grey,
                                                 match_geometry, at_match_scale, times);
  timer.Restart();
  if (!outputs.full_resolution) return encoding;
  encoding.disparity_px = UpsampleDisparity(encoding.disparity_px, full_size);
  auto upsample_codes = [&](cv::Mat& codes) {
    if (codes.empty()) return;
    cv::Mat full;
    cv::resize(codes, full, full_size, 0, 0, cv::INTER_NEAREST_EXACT);
    codes = full;
  };
  upsample_codes(encoding.height_code);
  upsample_codes(encoding.depth_code);
  if (outputs.rgbh) encoding.rgbh = PackRgbh(network_image, encoding.height_code);
  if (times != nullptr) times->Add("upsample", timer.ElapsedSeconds());
  return encoding;
}

StereoEncoding StereoEncoder::EncodeFromFixedPoint(
    const cv::Mat& fixed_point, const cv::Mat& network_image, const cv::Mat& left_grey,
    const StereoGeometry& geometry, const StereoOutputs& outputs, StageTimes* times) {
  STEREODET_CHECK(fixed_point.type() == CV_16SC1) << "expected OpenCV's CV_16SC1 disparity";
  STEREODET_CHECK(network_image.type() == CV_8UC3 &&
                  (!outputs.rgbh || network_image.size() == fixed_point.size()))
      << "network image must be CV_8UC3 (of the disparity's size for RGB-H)";
  STEREODET_CHECK(left_grey.type() == CV_8UC1 && left_grey.size() == fixed_point.size())
      << "left grey image must be CV_8UC1 of the disparity's size";
  Timer timer;
  StereoEncoding encoding;
  encoding.network_image = network_image;
  // The ground fit samples the fixed-point disparity directly, so that the float disparity can be
  // written in the same pass as everything else.
  encoding.ground = FitGroundPlane(fixed_point, geometry, match_ground_);
  if (times != nullptr) times->Add("ground", timer.ElapsedSeconds());
  timer.Restart();

  const int rows = fixed_point.rows, cols = fixed_point.cols;
  const HeightQuantization& hq = options_.height;
  const DepthQuantization& dq = options_.depth;
  const PointCloudOptions& pc = options_.points;
  const GroundPlane& plane = encoding.ground.plane;

  // Depth and depth code depend only on OpenCV's integer disparity (1/16 px steps): tabulate them.
  const DisparityOptions& matching = matcher_.matching_options();  // the search at this grid
  const int lut_size = (matching.min_disparity + matching.num_disparities) * 16 + 16;
  std::vector<float> depth_lut(lut_size);
  std::vector<uint16_t> depth_code_lut(lut_size);
  for (int raw = 1; raw < lut_size; ++raw) {
    const double depth = geometry.DepthFromDisparity(raw / 16.0);
    depth_lut[raw] = static_cast<float>(depth);
    depth_code_lut[raw] = dq.Quantize(depth);
  }
  // Ray through pixel (u, v): K^-1 [u, v, 1] = (ray_u[u], ray_v(v), 1). Height and velo coordinates
  // are affine in z along the ray, so they split into a per-column and a per-row term. Floats
  // suffice here (1e-7 relative: 10 um at 80 m) and halve the work of the point cloud.
  const Eigen::Vector3d& n = plane.normal_in_rect;
  const Eigen::Vector3d& c2 = geometry.camera2_in_rect;
  const float height_at_camera = static_cast<float>(plane.HeightAbove(c2));
  const Eigen::Matrix3d rotation = geometry.velo_from_rect.linear();
  const Eigen::Vector3d velo_at_camera = geometry.velo_from_rect * c2;
  std::vector<float> height_u(cols), velo_ux(cols), velo_uy(cols), velo_uz(cols);
  for (int u = 0; u < cols; ++u) {
    const double ray_u = (u - geometry.cx_px) / geometry.focal_px;
    height_u[u] = static_cast<float>(n.x() * ray_u);
    const Eigen::Vector3d velo_u = rotation.col(0) * ray_u;
    velo_ux[u] = static_cast<float>(velo_u.x());
    velo_uy[u] = static_cast<float>(velo_u.y());
    velo_uz[u] = static_cast<float>(velo_u.z());
  }
  const float height_min = static_cast<float>(hq.min_m), height_max = static_cast<float>(hq.max_m);
  const float height_scale =
      static_cast<float>((HeightQuantization::kLevels - 1) / (hq.max_m - hq.min_m));
  const float max_depth = static_cast<float>(pc.max_depth_m);
  const float min_point_height = static_cast<float>(pc.min_height_m);
  const float max_point_height = static_cast<float>(pc.max_height_m);
  const float velo_cx = static_cast<float>(velo_at_camera.x());
  const float velo_cy = static_cast<float>(velo_at_camera.y());
  const float velo_cz = static_cast<float>(velo_at_camera.z());

  encoding.disparity_px.create(rows, cols, CV_32FC1);
  encoding.height_code.create(rows, cols, CV_16UC1);
  if (outputs.depth) encoding.depth_code.create(rows, cols, CV_16UC1);
  if (outputs.rgbh) encoding.rgbh.create(rows, cols, CV_8UC3);
  constexpr int kRowsPerBlock = 8;
  const int blocks = (rows + kRowsPerBlock - 1) / kRowsPerBlock;
  // Points go to a scratch buffer kept between frames (at most one per pixel, a block of rows at a
  // fixed offset), so no memory is allocated or page-faulted in the loop; then they are compacted.
  std::vector<size_t> block_counts(blocks, 0);
  if (outputs.points && scratch_points_.size() < static_cast<size_t>(rows) * cols) {
    scratch_points_.resize(static_cast<size_t>(rows) * cols);
  }

  cv::parallel_for_(cv::Range(0, blocks), [&](const cv::Range& range) {
    for (int block = range.start; block < range.end; ++block) {
      const int v_begin = block * kRowsPerBlock;
      const int v_end = std::min(rows, v_begin + kRowsPerBlock);
      VeloPoint* const block_begin =
          outputs.points ? scratch_points_.data() + static_cast<size_t>(v_begin) * cols : nullptr;
      VeloPoint* point_out = block_begin;
      for (int v = v_begin; v < v_end; ++v) {
        const int16_t* raw = fixed_point.ptr<int16_t>(v);
        const uint8_t* bgr = network_image.ptr<uint8_t>(v);
        const uint8_t* grey = left_grey.ptr<uint8_t>(v);
        float* disparity_out = encoding.disparity_px.ptr<float>(v);
        uint16_t* height_out = encoding.height_code.ptr<uint16_t>(v);
        uint16_t* depth_out = outputs.depth ? encoding.depth_code.ptr<uint16_t>(v) : nullptr;
        uint8_t* rgbh_out = outputs.rgbh ? encoding.rgbh.ptr<uint8_t>(v) : nullptr;
        const double ray_v = (v - geometry.cy_px) / geometry.FocalY();
        const float height_v = static_cast<float>(n.y() * ray_v + n.z());
        const Eigen::Vector3d velo_v = rotation.col(1) * ray_v + rotation.col(2);
        const float velo_vx = static_cast<float>(velo_v.x());
        const float velo_vy = static_cast<float>(velo_v.y());
        const float velo_vz = static_cast<float>(velo_v.z());
        for (int u = 0; u < cols; ++u) {
          const int d = raw[u];
          uint16_t code = 0;
          disparity_out[u] = d > 0 ? static_cast<float>(d) * (1.0f / 16.0f) : kInvalidDisparity;
          if (d > 0) {
            // Beyond the table only if OpenCV ever returned more than its range; compute directly.
            const float z = d < lut_size
                                ? depth_lut[d]
                                : static_cast<float>(geometry.DepthFromDisparity(d / 16.0));
            const float height = height_at_camera + z * (height_u[u] + height_v);
            // + 1.5 then truncation = 1 + round() for the non-negative argument.
            code = static_cast<uint16_t>(
                (std::clamp(height, height_min, height_max) - height_min) * height_scale + 1.5f);
            if (depth_out != nullptr)
              depth_out[u] = d < lut_size ? depth_code_lut[d] : dq.Quantize(z);
            if (point_out != nullptr && z <= max_depth && height >= min_point_height &&
                height <= max_point_height) {
              *point_out++ = {velo_cx + z * (velo_ux[u] + velo_vx),
                              velo_cy + z * (velo_uy[u] + velo_vy),
                              velo_cz + z * (velo_uz[u] + velo_vz), ReflectanceFromGrey(grey[u])};
            }
          } else if (depth_out != nullptr) {
            depth_out[u] = 0;
          }
          height_out[u] = code;
          if (rgbh_out != nullptr) {
            rgbh_out[3 * u + 0] = static_cast<uint8_t>((bgr[3 * u + 0] & 0xF8) | (code & 7));
            rgbh_out[3 * u + 1] = static_cast<uint8_t>((bgr[3 * u + 1] & 0xF8) | ((code >> 3) & 7));
            rgbh_out[3 * u + 2] = static_cast<uint8_t>((bgr[3 * u + 2] & 0xF8) | (code >> 6));
          }
        }
      }
      block_counts[block] = static_cast<size_t>(point_out - block_begin);
    }
  });
  if (outputs.points) {
    size_t total = 0;
    for (size_t count : block_counts) total += count;
    encoding.points.reserve(total);
    for (int block = 0; block < blocks; ++block) {
      const VeloPoint* begin =
          scratch_points_.data() + static_cast<size_t>(block) * kRowsPerBlock * cols;
      encoding.points.insert(encoding.points.end(), begin, begin + block_counts[block]);
    }
    if (pc.beams > 0) encoding.points = SubsampleToBeams(encoding.points, pc);
  }
  if (times != nullptr) times->Add("encode", timer.ElapsedSeconds());
  return encoding;
}

}  // namespace stereodet
