// Training data of the two-stage detector: the frames of a split with their objects as training
// targets and, for RGB-D models, the stereo depth and height codes (computed once, kept in memory
// at the network's resolution). Augmentation, fully determined by a sample's seed: a horizontal
// flip of image, geometry and boxes together (depth and height above the ground do not change
// under a flip), and photometric jitter of the colour only (train_data.h's JitterColour). Samples
// are made in the caller's thread, in order: nothing here runs ahead asynchronously, so a training
// step depends only on (seed, epoch, frame).
#ifndef STEREODET_MODELS_RPN_RPN_DATA_H_
#define STEREODET_MODELS_RPN_RPN_DATA_H_

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/train_data.h"
#include "stereodet/stereo/stereo_encoder.h"
#include "stereodet/util/progress.h"

namespace stereodet {

// The ignore regions of the labels (LabelTargetOptions, train_data.h) and the two-stage detector's
// own settings.
struct RpnDataOptions : LabelTargetOptions {
  bool augment = true;
  double flip_probability = 0.5;
  // Photometric jitter (only brightness, contrast and saturation are used).
  AugmentOptions colour;
  // Stereo pipeline for the RGB-D geometry (disparity, ground plane, height and depth codes).
  StereoOptions stereo;
  int threads = 0;  // for the one-off stereo pass (0 = all cores)
  void Check() const;
};

// A frame held in memory for training.
struct RpnFrame : LabelledImageFrame {
  cv::Mat depth_code, height_code;  // CV_16UC1 at the network's size (empty for rgb)
};

struct RpnSample {
  PlanarImage input;
  std::vector<TargetBox> objects;  // network px
};

// The stereo depth and height codes of one frame at full resolution (StereoEncoder, with
// `stereo`); `network_image` is the left image the network sees (blurred when stereo.blur asks).
struct RpnGeometry {
  cv::Mat network_image, depth_code, height_code;
};
RpnGeometry ComputeRpnGeometry(const FramePaths& paths, const StereoOptions& stereo);

// The network input of a frame at full resolution: the image resized with INTER_AREA, the codes
// nearest-neighbour (codes must not be interpolated), EncodeRpnInput.
PlanarImage PrepareRpnInput(const cv::Mat& bgr, const cv::Mat& depth_code,
                            const cv::Mat& height_code, const RpnConfig& config,
                            const DepthQuantization& depth = {});

class RpnTrainingData : public TrainingFrameSet<RpnFrame, RpnConfig, RpnDataOptions> {
 public:
  // Reads every label file and, for RGB-D, runs stereo on every frame (parallel, with progress).
  // Throws std::runtime_error listing missing files (first few) before any work.
  RpnTrainingData(const KittiDataset& dataset, const std::vector<std::string>& ids,
                  const RpnConfig& config, const RpnDataOptions& options,
                  const ProgressOptions& progress = {});
  using TrainingFrameSet::TrainingFrameSet;  // from frames in memory

  // The augmented, encoded sample of frame `index`; the same seed gives the same sample.
  RpnSample Sample(int index, uint64_t seed) const;
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_DATA_H_
