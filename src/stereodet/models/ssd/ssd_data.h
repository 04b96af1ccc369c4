// Training data for the SSD: frames of a KITTI-format split, their labels as training targets, the
// stereo height codes (computed once, cached in memory at the network's resolution), augmentation
// that keeps the height consistent with the image, and a loader that builds batches on its own
// thread while the network trains.
//
// Augmentation (per sample, fully determined by its seed):
//   - zoom: a window of the image's aspect ratio, 1/zoom of its size, zoom log-uniform in
//     [min_zoom, max_zoom], at a uniform position (zoom < 1 pads around the image: grey colour,
//     height code 0 = "no stereo"); colour is cropped from the full-resolution image and resized
//     with INTER_AREA, the height codes are warped from the cache with the same affine map, nearest
//     neighbour (codes must not be interpolated);
//   - horizontal flip of colour, height and boxes together (height above the ground does not change
//     under a flip or a zoom, so the codes themselves are kept);
//   - photometric jitter (brightness, contrast, saturation) on the colour only, before encoding.
#ifndef STEREODET_MODELS_SSD_SSD_DATA_H_
#define STEREODET_MODELS_SSD_SSD_DATA_H_

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <filesystem>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/object.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/models/train_data.h"
#include "stereodet/stereo/stereo_encoder.h"
#include "stereodet/util/progress.h"

namespace stereodet {

// The ignore regions of the labels (LabelTargetOptions, train_data.h) and the SSD's own settings.
struct SsdDataOptions : LabelTargetOptions {
  AugmentOptions augment;
  MatchOptions match;
  // Stereo pipeline for the height codes (disparity, ground plane, 9-bit quantization). Blur is
  // applied at evaluation only (ssd_detect.h), never here.
  StereoOptions stereo;
  // Read the height codes from this `stereodet stereo` folder (stereo/dataset_encoder.h,
  // ReadStereoFolderHeight) instead of matching; empty = match. Its stereo.json's settings must be
  // `stereo` (TrainSsd makes them so), and its run.json's data the dataset's.
  std::filesystem::path stereo_dir;
  // Threads for the one-off stereo pass over the split (0 = all cores).
  int threads = 0;
  void Check() const;
};

// One frame's network input at the model's size, from a full-resolution BGR image and, for RGB-H
// encodings, the height codes: at the image's size, or at the stereo match size (match_scale < 1,
// StereoOutputs::full_resolution false), resized nearest-neighbour to the network's size unless
// they have it already. The inference path.
PlanarImage PrepareNetworkInput(const cv::Mat& bgr, const cv::Mat& height_code,
                                const SsdConfig& config);

// A frame held in memory for training.
struct TrainingFrame : LabelledImageFrame {
  cv::Mat height_code;  // CV_16UC1 at the network's input size (empty for rgb)
};

struct TrainSample {
  PlanarImage input;
  MatchResult match;
  std::vector<TargetBox> targets;  // after augmentation, network-input px
};

// The frames of one split, ready to sample from. Construction reads every label file and, for RGB-H
// encodings, runs the stereo pipeline on every frame (in parallel, with progress).
class SsdTrainingData : public TrainingFrameSet<TrainingFrame, SsdConfig, SsdDataOptions> {
 public:
  // Throws std::runtime_error listing missing files (first few) before doing any work.
  SsdTrainingData(const KittiDataset& dataset, const std::vector<std::string>& ids,
                  const SsdConfig& config, const SsdDataOptions& options,
                  const ProgressOptions& progress = {});
  using TrainingFrameSet::TrainingFrameSet;  // from frames in memory

  const std::vector<DefaultBox>& default_boxes() const { return default_boxes_; }

  // The augmented, encoded sample of frame `index`; the same seed gives the same sample.
  TrainSample Sample(int index, uint64_t seed) const;
  // Samples `indices` (seeds[i] for indices[i]) into one batch.
  TrainBatch MakeBatch(const std::vector<int>& indices, const std::vector<uint64_t>& seeds) const;

 private:
  std::vector<DefaultBox> default_boxes_ = GenerateDefaultBoxes(config_.boxes);
};

// Builds the batches of one epoch on a background thread, up to `capacity` batches ahead of the
// consumer (a bounded queue: memory stays small and the producer waits when training is slower).
class BatchLoader {
 public:
  // The batches of `batches` (indices into `data`), in order. `data` must outlive the loader.
  BatchLoader(const SsdTrainingData& data, std::vector<std::vector<int>> batches, uint64_t seed,
              int epoch, int capacity = 3);
  // Batches of consecutive slices of `order` of `batch_size` frames (the last may be smaller).
  BatchLoader(const SsdTrainingData& data, const std::vector<int>& order, int batch_size,
              uint64_t seed, int epoch, int capacity = 3);
  ~BatchLoader();  // stops the producer and joins it
  BatchLoader(const BatchLoader&) = delete;
  BatchLoader& operator=(const BatchLoader&) = delete;

  int num_batches() const { return num_batches_; }
  // The next batch, or nullopt after the last. Rethrows an exception of the producer (a frame that
  // cannot be read).
  std::optional<TrainBatch> Next();

 private:
  void Produce();

  const SsdTrainingData& data_;
  std::vector<std::vector<int>> batches_;
  uint64_t seed_;
  int epoch_;
  int capacity_;
  int num_batches_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<TrainBatch> queue_;
  bool finished_ = false;  // the producer is done (or failed)
  bool stop_ = false;      // the consumer is gone
  std::exception_ptr error_;
  std::thread thread_;  // last: starts after everything above is initialised
};

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_SSD_DATA_H_
