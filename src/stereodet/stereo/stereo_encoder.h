// The whole per-frame stereo pipeline, fused for speed: disparity -> ground plane -> height and
// depth codes, RGB-H packing and the point cloud in one parallel pass over the rows.
//
// It produces exactly what the separate functions of reprojection.h, rgbh.h and point_cloud.h
// produce (they are its reference in the tests), but reads OpenCV's fixed-point disparity once,
// uses look-up tables indexed by it for depth, and per-row/per-column tables for the height, so
// everything after the matcher costs a few percent of the matcher (benchmarks/stereo_benchmark.cc).
#ifndef STEREODET_STEREO_STEREO_ENCODER_H_
#define STEREODET_STEREO_STEREO_ENCODER_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/stereo/degradation.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/point_cloud.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/util/timer.h"

namespace stereodet {

// With disparity.match_scale < 1 (disparity.h) the pair is matched at MatchSize() and everything
// after the matcher (ground fit, depth and height codes, points) runs on that grid with the
// geometry scaled to it (StereoGeometry::Scaled): the ground fit samples every
// max(1, round(sample_step_px x match_scale))-th row and column there, so it sees about as many
// points as at full resolution. StereoOutputs::full_resolution says at which size the images come
// out.
struct StereoOptions {
  DisparityOptions disparity;
  GroundPlaneOptions ground;
  HeightQuantization height;
  DepthQuantization depth;
  PointCloudOptions points;
  BlurOptions blur;
  void Check() const;
};

// The settings that decide the disparity, the ground plane and the height codes, as one JSON object
// (pretty, 2 spaces, trailing newline): {"disparity": {...}, "ground": {...}, "height_code":
// {...}}, every field under its name in DisparityOptions (bm_*, sgbm_*, wls_* for the nested
// ones; match_scale among them), GroundPlaneOptions and HeightQuantization. OUT/stereo.json holds
// these (with the other outputs' settings) and model.json records them for RGB-H models.
std::string StereoSettingsJson(const StereoOptions& options);

// Reads those settings back into `defaults` (a copy is returned): a key that is absent keeps its
// value in `defaults`, so a file written before a setting was recorded reads as that default
// (disparity.match_scale: 1, full resolution, with the default `defaults`).
// Throws ParseError naming `source` and the key for a value of the wrong type or a bad name, and
// std::invalid_argument (Check) for a value out of range.
StereoOptions StereoOptionsFromJson(const std::string& text, const std::string& source,
                                    const StereoOptions& defaults = {});

// The settings of StereoSettingsJson that differ between `recorded` and `requested`, as "key:
// RECORDED (requested: REQUESTED)" joined by "; " (keys "disparity.uniqueness_ratio"); empty when
// they agree.
std::string DifferingStereoSettings(const StereoOptions& recorded, const StereoOptions& requested);

// What Encode should produce besides the disparity, the ground fit and the height codes.
struct StereoOutputs {
  bool rgbh = true;     // packed RGB-H image
  bool depth = false;   // depth codes
  bool points = false;  // point cloud
  // With match_scale < 1: true = disparity_px, height_code, depth_code and rgbh at the input
  // images' size (the match-scale results upsampled by UpsampleDisparity / nearest neighbour,
  // INTER_NEAREST_EXACT); false = at the match size, disparity in match-scale px (what a network
  // of about that size needs, without a full-resolution pass; rgbh must then be false). No effect
  // at match_scale 1.
  bool full_resolution = true;
};

// Sizes: network_image is the input's size. With match_scale 1, or full_resolution, the other
// images are too; else they are of the match size (DisparityOptions::MatchSize). The point cloud
// has a point per pixel of the match-scale grid at most (about match_scale^2 as many as at 1).
struct StereoEncoding {
  cv::Mat network_image;  // CV_8UC3: the left image the network sees (blurred when blur is on)
  cv::Mat disparity_px;   // CV_32FC1, kInvalidDisparity where none; px of its own size
  GroundPlaneFit ground;
  cv::Mat height_code;  // CV_16UC1, 0 = no stereo, 1..511
  cv::Mat depth_code;   // CV_16UC1, 0 = no stereo (empty unless outputs.depth)
  cv::Mat rgbh;         // CV_8UC3 packed RGB-H of network_image (empty unless outputs.rgbh)
  std::vector<VeloPoint> points;  // velo frame (empty unless outputs.points)
};

// Not thread-safe (it owns an OpenCV matcher): use one per thread. Internally parallel (OpenCV).
class StereoEncoder {
 public:
  explicit StereoEncoder(const StereoOptions& options = {});
  const StereoOptions& options() const { return options_; }

  // Requires: rectified 8-bit BGR images (CV_8UC3) of the same size; `geometry` of that size.
  // Stage times, when `times` is not null, are added under "blur", "grey" (with the resize to the
  // match size), "disparity" (OpenCV's matcher), "ground", "encode" and, with match_scale < 1 and
  // outputs.full_resolution, "upsample".
  StereoEncoding Encode(const cv::Mat& left_bgr, const cv::Mat& right_bgr,
                        const StereoGeometry& geometry, const StereoOutputs& outputs = {},
                        StageTimes* times = nullptr);

  // The part after the matcher, from OpenCV's CV_16SC1 disparity (x16) of `left_grey`, on their
  // grid (the match size; `geometry` of that grid), with no upsampling; exposed for the benchmark.
  // `network_image` is the BGR image to pack (of that size when outputs.rgbh; any size else: it is
  // only returned); `left_grey` gives the reflectance.
  StereoEncoding EncodeFromFixedPoint(const cv::Mat& fixed_point, const cv::Mat& network_image,
                                      const cv::Mat& left_grey, const StereoGeometry& geometry,
                                      const StereoOutputs& outputs, StageTimes* times = nullptr);

  DisparityMatcher& matcher() { return matcher_; }

 private:
  StereoOptions options_;
  GroundPlaneOptions match_ground_;  // options_.ground with the sample step at the match scale
  DisparityMatcher matcher_;
  std::vector<VeloPoint> scratch_points_;  // reused between frames: one slot per pixel
};

}  // namespace stereodet

#endif  // STEREODET_STEREO_STEREO_ENCODER_H_
