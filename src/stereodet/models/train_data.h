// What the families' training data share: the order frames are visited in, each sample's seed,
// the image augmentation's options and its photometric jitter, and a frame's 2D labels as training
// targets. Every draw is a function of (run seed, epoch, frame), never of the order or the thread
// that made it, so a resumed training draws what an uninterrupted one draws.
#ifndef STEREODET_MODELS_TRAIN_DATA_H_
#define STEREODET_MODELS_TRAIN_DATA_H_

#include <cstdint>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/object.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/progress.h"

namespace stereodet {

// The image augmentation of the single-shot detector (ssd/ssd_data.h: zoom, flip, jitter); the
// two-stage detector (rpn/) uses its photometric jitter.
struct AugmentOptions {
  bool enabled = true;
  double flip_probability = 0.5;
  // Window = image / zoom, zoom log-uniform in [min_zoom, max_zoom] (< 1 zooms out, > 1 crops in).
  double min_zoom = 0.8;
  double max_zoom = 1.6;
  // Colour only: value += U(-brightness, brightness) * 255; value = mean + U(1 - contrast,
  // 1 + contrast) * (value - mean); saturation blends with grey by U(1 - saturation, 1 +
  // saturation).
  double brightness = 0.12;
  double contrast = 0.25;
  double saturation = 0.25;
  // An object that keeps less than this fraction of its box inside the window becomes an ignore
  // region (neither positive nor negative).
  double min_visible_fraction = 0.5;
  void Check() const;  // throws std::invalid_argument
};

// The photometric jitter of AugmentOptions (brightness, contrast, saturation) on an 8-bit BGR
// image in place, drawing three numbers from `rng`.
void JitterColour(cv::Mat& bgr, const AugmentOptions& options, std::mt19937_64& rng);

// Which labels the image families (ssd, rpn) train on as ignore regions (SsdDataOptions and
// RpnDataOptions are these plus their own).
struct LabelTargetOptions {
  // Label types that become ignore regions; other types not among the model's classes are
  // background. Van and Person_sitting are KITTI's "neighbouring classes" of Car and Pedestrian:
  // detecting them is neither right nor wrong in KITTI's evaluation, so they are not negatives.
  std::vector<std::string> ignore_types = {"DontCare", "Van", "Person_sitting"};
  // Objects of a class whose box is less tall than this (original image px) become ignore regions:
  // KITTI's evaluation ignores anything below 25 px, so they are neither taught nor punished.
  double min_object_height_px = 20.0;
  void Check() const;  // throws std::invalid_argument
};

// The training targets of a frame's labels in original image px: classes -> 1 + index in `classes`,
// ignore types and too-small objects (`options`) -> kIgnoreLabel, anything else dropped.
std::vector<TargetBox> TargetsFromLabels(const std::vector<Object>& labels,
                                         const std::vector<std::string>& classes,
                                         const LabelTargetOptions& options);

// What the image families (ssd, rpn) keep of every training frame; each adds its stereo codes.
struct LabelledImageFrame {
  std::string id;
  std::filesystem::path image_path;  // left image (image_2), read at every use
  std::vector<TargetBox> targets;    // original image px (TargetsFromLabels)
};

// The frames of one split an image family trains on, in memory, with the model's config and the
// family's data options (SsdTrainingData, RpnTrainingData: each adds how it reads its frames and
// samples one). `Frame` is a LabelledImageFrame with the family's fields.
template <typename Frame, typename Config, typename Options>
class TrainingFrameSet {
 public:
  // From frames already in memory (tests; the families read theirs). Checks `config` and
  // `options` (their Check(): std::invalid_argument).
  TrainingFrameSet(std::vector<Frame> frames, const Config& config, const Options& options)
      : frames_(std::move(frames)), config_(config), options_(options) {
    config.Check();
    options.Check();
  }

  int size() const { return static_cast<int>(frames_.size()); }
  const Frame& frame(int index) const { return frames_[index]; }
  const Config& config() const { return config_; }
  // Targets of the model's classes (label >= 1, not ignore regions) over all frames.
  int NumObjects() const {
    int count = 0;
    for (const Frame& f : frames_) {
      for (const TargetBox& t : f.targets) count += t.label >= 1 ? 1 : 0;
    }
    return count;
  }

 protected:
  std::vector<Frame> frames_;
  Config config_;
  Options options_;
};

// One Frame (a LabelledImageFrame with a family's fields) per id of `ids`, in their order, read in
// parallel on `threads` (0 = all cores) with a progress line named `stage`: its id, its left
// image's path and its label's targets (TargetsFromLabels of `classes` and `targets`), then
// `more(paths, frame)` adds the family's fields. Throws what reading throws, naming the file.
template <typename Frame>
std::vector<Frame> ReadLabelledFrames(const KittiDataset& dataset,
                                      const std::vector<std::string>& ids,
                                      const std::vector<std::string>& classes,
                                      const LabelTargetOptions& targets, int threads,
                                      const std::string& stage, const ProgressOptions& progress,
                                      const std::function<void(const FramePaths&, Frame&)>& more) {
  std::vector<Frame> frames(ids.size());
  ProgressReporter reporter(stage, static_cast<int64_t>(ids.size()), progress);
  ParallelFor(
      ids.size(),
      [&](size_t i) {
        const FramePaths paths = dataset.Paths(ids[i]);
        Frame& frame = frames[i];
        frame.id = ids[i];
        frame.image_path = paths.image_left;
        frame.targets = TargetsFromLabels(ReadObjects(paths.label).objects, classes, targets);
        more(paths, frame);
        reporter.Add(1);
      },
      threads);
  reporter.Finish();
  return frames;
}

// A seed per (run seed, epoch, frame), independent of the order frames are visited in.
uint64_t SampleSeed(uint64_t seed, int epoch, int frame_index);
// Frame order of an epoch: a permutation of 0..n-1 drawn from (seed, epoch).
std::vector<int> EpochOrder(int n, uint64_t seed, int epoch);

// A batch's training samples, in the batch's order: make(frame, SampleSeed(seed, epoch, frame))
// for each frame index of `batch_frames`, in parallel on `threads` threads (0 = all cores). Each
// sample draws from its own seed, so the batch is the same on any number of threads and in any
// epoch a resumed training redoes.
template <typename Make>
auto MakeBatchSamples(const std::vector<int>& batch_frames, uint64_t seed, int epoch, int threads,
                      Make make) {
  std::vector<decltype(make(0, uint64_t{0}))> samples(batch_frames.size());
  ParallelFor(
      samples.size(),
      [&](size_t k) {
        const int frame = batch_frames[k];
        samples[k] = make(frame, SampleSeed(seed, epoch, frame));
      },
      threads);
  return samples;
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_TRAIN_DATA_H_
