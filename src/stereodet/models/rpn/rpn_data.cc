#include "stereodet/models/rpn/rpn_data.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"

namespace stereodet {

void RpnDataOptions::Check() const {
  colour.Check();
  stereo.Check();
  LabelTargetOptions::Check();
  STEREODET_CHECK(flip_probability >= 0.0 && flip_probability <= 1.0)
      << "flip_probability must be in [0, 1], got " << flip_probability;
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
}

namespace {

cv::Mat ResizeCodes(const cv::Mat& code, cv::Size size) {
  cv::Mat resized;
  cv::resize(code, resized, size, 0, 0, cv::INTER_NEAREST);
  return resized;
}

}  // namespace

RpnGeometry ComputeRpnGeometry(const FramePaths& paths, const StereoOptions& stereo) {
  const cv::Mat left = ReadColourImage(paths.image_left);
  const cv::Mat right = ReadColourImage(paths.image_right);
  CheckStereoPairSize(left, right, paths.image_left, paths.image_right);
  CheckImageFitsMatcher(stereo.disparity, left.size(), paths.image_left);
  // One encoder per call: StereoEncoder is not thread-safe and cheap to make.
  StereoEncoder encoder(stereo);
  StereoOutputs outputs;
  outputs.rgbh = false;
  outputs.depth = true;
  StereoEncoding encoding = encoder.Encode(
      left, right, StereoGeometry::FromCalibration(ReadCalibration(paths.calib)), outputs);
  return {encoding.network_image, encoding.depth_code, encoding.height_code};
}

PlanarImage PrepareRpnInput(const cv::Mat& bgr, const cv::Mat& depth_code,
                            const cv::Mat& height_code, const RpnConfig& config,
                            const DepthQuantization& depth) {
  const cv::Size size(config.input_width, config.input_height);
  cv::Mat resized;
  cv::resize(bgr, resized, size, 0, 0, cv::INTER_AREA);
  if (config.input != RpnInput::kRgbd) return EncodeRpnInput(resized, {}, {}, config.input, depth);
  STEREODET_CHECK(depth_code.size() == bgr.size() && height_code.size() == bgr.size())
      << "depth and height codes must have the image's size";
  return EncodeRpnInput(resized, ResizeCodes(depth_code, size), ResizeCodes(height_code, size),
                        config.input, depth);
}

RpnTrainingData::RpnTrainingData(const KittiDataset& dataset, const std::vector<std::string>& ids,
                                 const RpnConfig& config, const RpnDataOptions& options,
                                 const ProgressOptions& progress)
    : TrainingFrameSet({}, config, options) {
  STEREODET_CHECK(!ids.empty()) << "no frames to train on";
  const bool geometry = config.input == RpnInput::kRgbd;
  RequiredFiles required;
  required.image_left = required.label = true;
  required.image_right = required.calib = geometry;
  CheckRequiredFiles(dataset, ids, required);
  const cv::Size network_size(config.input_width, config.input_height);
  StereoOptions stereo = options.stereo;
  stereo.blur.sigma_px = 0.0;  // training sees sharp images; blur is an evaluation setting
  frames_ = ReadLabelledFrames<RpnFrame>(
      dataset, ids, config.classes, options, options.threads, geometry ? "stereo" : "labels",
      progress, [&](const FramePaths& paths, RpnFrame& frame) {
        if (!geometry) return;
        const RpnGeometry g = ComputeRpnGeometry(paths, stereo);
        frame.depth_code = ResizeCodes(g.depth_code, network_size);
        frame.height_code = ResizeCodes(g.height_code, network_size);
      });
}

RpnSample RpnTrainingData::Sample(int index, uint64_t seed) const {
  STEREODET_CHECK(index >= 0 && index < size()) << "frame index " << index << " out of range";
  const RpnFrame& frame = frames_[index];
  const int net_w = config_.input_width, net_h = config_.input_height;
  const bool geometry = config_.input == RpnInput::kRgbd;
  if (geometry) {
    STEREODET_CHECK(
        frame.depth_code.type() == CV_16UC1 && frame.depth_code.size() == cv::Size(net_w, net_h) &&
        frame.height_code.type() == CV_16UC1 && frame.height_code.size() == cv::Size(net_w, net_h))
        << "frame " << frame.id << ": depth and height codes must be CV_16UC1 of the network's "
        << "size";
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const cv::Mat full = ReadColourImage(frame.image_path);
  cv::Mat bgr;
  cv::resize(full, bgr, cv::Size(net_w, net_h), 0, 0, cv::INTER_AREA);
  const bool flip = options_.augment && uniform(rng) < options_.flip_probability;
  // The stored codes are shared, never written: a flip goes into new matrices. (cv::flip into a
  // header of the frame's own buffer flipped the stored codes in place, so every later sample of
  // the frame had its geometry mirrored against its image until the next flip; a resumed
  // training, which recomputes the codes, then saw other inputs than an uninterrupted one.)
  cv::Mat depth, height;
  if (flip) {
    cv::flip(bgr, bgr, 1);
    if (geometry) {
      cv::flip(frame.depth_code, depth, 1);
      cv::flip(frame.height_code, height, 1);
    }
  } else {
    depth = frame.depth_code;
    height = frame.height_code;
  }
  if (options_.augment) JitterColour(bgr, options_.colour, rng);
  RpnSample sample;
  sample.input = EncodeRpnInput(bgr, depth, height, config_.input, options_.stereo.depth);
  const double sx = static_cast<double>(net_w) / full.cols;
  const double sy = static_cast<double>(net_h) / full.rows;
  for (const TargetBox& t : frame.targets) {
    double l = t.box.left * sx, r = t.box.right * sx;
    if (flip) {
      l = net_w - l;
      r = net_w - r;
      std::swap(l, r);
    }
    const Box2D box{
        std::clamp(l, 0.0, double(net_w)), std::clamp(t.box.top * sy, 0.0, double(net_h)),
        std::clamp(r, 0.0, double(net_w)), std::clamp(t.box.bottom * sy, 0.0, double(net_h))};
    if (box.Width() < 1.0 || box.Height() < 1.0) continue;
    sample.objects.push_back({box, t.label});
  }
  return sample;
}

}  // namespace stereodet
