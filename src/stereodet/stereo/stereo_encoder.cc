#include "stereodet/stereo/stereo_encoder.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core/utility.hpp>

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

StereoEncoder::StereoEncoder(const StereoOptions& options)
    : options_(options), matcher_(options.disparity) {
  options_.Check();
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
  const cv::Mat left_grey = ToGrey(match_left);
  const cv::Mat right_grey = ToGrey(match_right);
  stage("grey");
  const cv::Mat fixed_point = matcher_.ComputeFixedPoint(left_grey, right_grey);
  stage("disparity");
  return EncodeFromFixedPoint(fixed_point, network_image, left_grey, geometry, outputs, times);
}

StereoEncoding StereoEncoder::EncodeFromFixedPoint(
    const cv::Mat& fixed_point, const cv::Mat& network_image, const cv::Mat& left_grey,
    const StereoGeometry& geometry, const StereoOutputs& outputs, StageTimes* times) {
  STEREODET_CHECK(fixed_point.type() == CV_16SC1) << "expected OpenCV's CV_16SC1 disparity";
  STEREODET_CHECK(network_image.type() == CV_8UC3 && network_image.size() == fixed_point.size())
      << "network image must be CV_8UC3 of the disparity's size";
  STEREODET_CHECK(left_grey.type() == CV_8UC1 && left_grey.size() == fixed_point.size())
      << "left grey image must be CV_8UC1 of the disparity's size";
  Timer timer;
  StereoEncoding encoding;
  encoding.network_image = network_image;
  // The ground fit samples the fixed-point disparity directly, so that the float disparity can be
  // written in the same pass as everything else.
  encoding.ground = FitGroundPlane(fixed_point, geometry, options_.ground);
  if (times != nullptr) times->Add("ground", timer.ElapsedSeconds());
  timer.Restart();

  const int rows = fixed_point.rows, cols = fixed_point.cols;
  const HeightQuantization& hq = options_.height;
  const DepthQuantization& dq = options_.depth;
  const PointCloudOptions& pc = options_.points;
  const GroundPlane& plane = encoding.ground.plane;

  // Depth and depth code depend only on OpenCV's integer disparity (1/16 px steps): tabulate them.
  const int lut_size =
      (options_.disparity.min_disparity + options_.disparity.num_disparities) * 16 + 16;
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
        const double ray_v = (v - geometry.cy_px) / geometry.focal_px;
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
