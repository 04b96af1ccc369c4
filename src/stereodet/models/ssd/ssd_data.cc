#include "stereodet/models/ssd/ssd_data.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"

namespace stereodet {

void SsdDataOptions::Check() const {
  augment.Check();
  match.Check();
  stereo.Check();
  LabelTargetOptions::Check();
  STEREODET_CHECK(threads >= 0) << "threads must be >= 0, got " << threads;
}

namespace {

cv::Mat ResizeHeightCodes(const cv::Mat& code, cv::Size size) {
  if (code.size() == size) return code;  // matched at the network's size (match_scale)
  cv::Mat resized;
  cv::resize(code, resized, size, 0, 0, cv::INTER_NEAREST);
  return resized;
}

}  // namespace

PlanarImage PrepareNetworkInput(const cv::Mat& bgr, const cv::Mat& height_code,
                                const SsdConfig& config) {
  const cv::Size size(config.InputWidth(), config.InputHeight());
  cv::Mat resized;
  cv::resize(bgr, resized, size, 0, 0, cv::INTER_AREA);
  cv::Mat code;
  if (UsesHeight(config.encoding)) {
    STEREODET_CHECK(height_code.type() == CV_16UC1 && !height_code.empty())
        << "height codes must be CV_16UC1 (of the image's or the match size)";
    code = ResizeHeightCodes(height_code, size);
  }
  return EncodeNetworkInput(resized, code, config.encoding);
}

// --- SsdTrainingData
// --------------------------------------------------------------------------------

SsdTrainingData::SsdTrainingData(const KittiDataset& dataset, const std::vector<std::string>& ids,
                                 const SsdConfig& config, const SsdDataOptions& options,
                                 const ProgressOptions& progress)
    : TrainingFrameSet({}, config, options) {
  STEREODET_CHECK(!ids.empty()) << "no frames to train on";
  const bool height = UsesHeight(config.encoding);
  RequiredFiles required;
  required.image_left = required.label = true;
  const bool from_folder = height && !options.stereo_dir.empty();
  required.image_right = required.calib = height && !from_folder;
  std::optional<StereoFolderRecord> folder;
  if (from_folder) {
    folder = ReadStereoFolder(options.stereo_dir);
    CheckStereoFolderData(*folder, dataset);
    const std::string differ = DifferingStereoSettings(options.stereo, folder->stereo);
    STEREODET_CHECK(differ.empty())
        << "--stereo " << options.stereo_dir.string()
        << ": its stereo.json differs from the training's settings: " << differ;
  }
  CheckRequiredFiles(dataset, ids, required);
  const cv::Size network_size(config.InputWidth(), config.InputHeight());
  frames_ = ReadLabelledFrames<TrainingFrame>(
      dataset, ids, config.classes, options, options.threads, height ? "stereo" : "labels",
      progress, [&](const FramePaths& paths, TrainingFrame& frame) {
        if (from_folder) {
          // At the match size, as the in-line path below has them (ReadStereoFolderHeight's
          // full-resolution codes, resized to the network, would differ).
          frame.height_code = ResizeHeightCodes(
              ReadStereoFolderHeightAtMatchScale(*folder, frame.id), network_size);
        } else if (height) {
          // One encoder per frame: StereoEncoder is not thread-safe and cheap to make.
          StereoEncoder encoder(options.stereo);
          const StereoGeometry geometry =
              StereoGeometry::FromCalibration(ReadCalibration(paths.calib));
          StereoOutputs outputs;
          outputs.rgbh = false;
          // At match_scale < 1 the codes stay at the match size (the network's, at 0.5 for a
          // network of half the image) and are resized from there at most.
          outputs.full_resolution = false;
          const cv::Mat left = ReadColourImage(paths.image_left);
          const cv::Mat right = ReadColourImage(paths.image_right);
          CheckStereoPairSize(left, right, paths.image_left, paths.image_right);
          CheckImageFitsMatcher(options.stereo.disparity, left.size(), paths.image_left);
          const StereoEncoding encoding = encoder.Encode(left, right, geometry, outputs);
          frame.height_code = ResizeHeightCodes(encoding.height_code, network_size);
        }
      });
}

TrainSample SsdTrainingData::Sample(int index, uint64_t seed) const {
  STEREODET_CHECK(index >= 0 && index < size()) << "frame index " << index << " out of range";
  const TrainingFrame& frame = frames_[index];
  const AugmentOptions& aug = options_.augment;
  const int net_w = config_.InputWidth(), net_h = config_.InputHeight();
  const bool height = UsesHeight(config_.encoding);
  if (height) {
    STEREODET_CHECK(frame.height_code.type() == CV_16UC1 &&
                    frame.height_code.size() == cv::Size(net_w, net_h))
        << "frame " << frame.id << ": height codes must be CV_16UC1 of the network's size";
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  const cv::Mat full = ReadColourImage(frame.image_path);
  const int full_w = full.cols, full_h = full.rows;

  // The window of the original image the network will see (integer px, may extend outside).
  int x0 = 0, y0 = 0, win_w = full_w, win_h = full_h;
  bool flip = false;
  if (aug.enabled) {
    const double zoom = std::exp(std::log(aug.min_zoom) +
                                 uniform(rng) * (std::log(aug.max_zoom) - std::log(aug.min_zoom)));
    win_w = std::max(1, static_cast<int>(std::lround(full_w / zoom)));
    win_h = std::max(1, static_cast<int>(std::lround(full_h / zoom)));
    const int slack_x = full_w - win_w, slack_y = full_h - win_h;
    x0 =
        std::min(0, slack_x) + static_cast<int>(std::floor(uniform(rng) * (std::abs(slack_x) + 1)));
    y0 =
        std::min(0, slack_y) + static_cast<int>(std::floor(uniform(rng) * (std::abs(slack_y) + 1)));
    flip = uniform(rng) < aug.flip_probability;
  }

  // Colour: crop (padding with grey outside the image), then resize to the network's size.
  cv::Mat window(win_h, win_w, CV_8UC3, cv::Scalar::all(128));
  const cv::Rect inside = cv::Rect(x0, y0, win_w, win_h) & cv::Rect(0, 0, full_w, full_h);
  if (inside.area() > 0) full(inside).copyTo(window(inside - cv::Point(x0, y0)));
  cv::Mat bgr;
  cv::resize(window, bgr, cv::Size(net_w, net_h), 0, 0,
             win_w >= net_w ? cv::INTER_AREA : cv::INTER_LINEAR);
  if (flip) cv::flip(bgr, bgr, 1);
  if (aug.enabled) JitterColour(bgr, aug, rng);

  // Original px -> network px.
  const double sx = static_cast<double>(net_w) / win_w, sy = static_cast<double>(net_h) / win_h;
  auto map_x = [&](double x) {
    const double u = (x - x0) * sx;
    return flip ? net_w - u : u;
  };
  auto map_y = [&](double y) { return (y - y0) * sy; };

  cv::Mat code;
  if (height) {
    // Cache px -> original px -> network px, as one affine map; nearest neighbour keeps codes
    // exact.
    const double cache_to_full_x = static_cast<double>(full_w) / net_w;
    const double cache_to_full_y = static_cast<double>(full_h) / net_h;
    double ax = cache_to_full_x * sx, bx = -x0 * sx;
    if (flip) {
      ax = -ax;
      bx = net_w - bx;
    }
    const cv::Matx23d affine(ax, 0, bx, 0, cache_to_full_y * sy, -y0 * sy);
    cv::warpAffine(frame.height_code, code, affine, cv::Size(net_w, net_h), cv::INTER_NEAREST,
                   cv::BORDER_CONSTANT, cv::Scalar(0));
  }

  TrainSample sample;
  sample.input = EncodeNetworkInput(bgr, code, config_.encoding);
  for (const TargetBox& target : frame.targets) {
    double l = map_x(target.box.left), r = map_x(target.box.right);
    if (l > r) std::swap(l, r);
    const Box2D mapped{l, map_y(target.box.top), r, map_y(target.box.bottom)};
    const Box2D clipped{std::clamp(mapped.left, 0.0, double(net_w)),
                        std::clamp(mapped.top, 0.0, double(net_h)),
                        std::clamp(mapped.right, 0.0, double(net_w)),
                        std::clamp(mapped.bottom, 0.0, double(net_h))};
    if (clipped.Width() < 1.0 || clipped.Height() < 1.0) continue;
    int64_t label = target.label;
    if (label >= 1 && clipped.Area() < aug.min_visible_fraction * mapped.Area())
      label = kIgnoreLabel;
    sample.targets.push_back({clipped, label});
  }
  sample.match = MatchDefaultBoxes(default_boxes_, sample.targets, options_.match);
  return sample;
}

TrainBatch SsdTrainingData::MakeBatch(const std::vector<int>& indices,
                                      const std::vector<uint64_t>& seeds) const {
  STEREODET_CHECK(indices.size() == seeds.size() && !indices.empty())
      << "need one seed per frame and at least one frame";
  TrainBatch batch;
  batch.batch_size = static_cast<int>(indices.size());
  batch.channels = NetworkInputChannels(config_.encoding);
  batch.height = config_.InputHeight();
  batch.width = config_.InputWidth();
  const size_t image_size = static_cast<size_t>(batch.channels) * batch.height * batch.width;
  batch.images.reserve(indices.size() * image_size);
  for (size_t i = 0; i < indices.size(); ++i) {
    TrainSample sample = Sample(indices[i], seeds[i]);
    batch.images.insert(batch.images.end(), sample.input.data.begin(), sample.input.data.end());
    batch.labels.insert(batch.labels.end(), sample.match.labels.begin(), sample.match.labels.end());
    batch.deltas.insert(batch.deltas.end(), sample.match.deltas.begin(), sample.match.deltas.end());
    batch.num_positive += sample.match.num_positive;
  }
  return batch;
}

// --- BatchLoader
// ------------------------------------------------------------------------------------

namespace {

std::vector<std::vector<int>> ConsecutiveBatches(const std::vector<int>& order, int batch_size) {
  STEREODET_CHECK(batch_size >= 1) << "batch size must be >= 1, got " << batch_size;
  std::vector<std::vector<int>> batches;
  for (size_t begin = 0; begin < order.size(); begin += batch_size) {
    const size_t end = std::min(order.size(), begin + batch_size);
    batches.emplace_back(order.begin() + begin, order.begin() + end);
  }
  return batches;
}

}  // namespace

BatchLoader::BatchLoader(const SsdTrainingData& data, const std::vector<int>& order, int batch_size,
                         uint64_t seed, int epoch, int capacity)
    : BatchLoader(data, ConsecutiveBatches(order, batch_size), seed, epoch, capacity) {}

BatchLoader::BatchLoader(const SsdTrainingData& data, std::vector<std::vector<int>> batches,
                         uint64_t seed, int epoch, int capacity)
    : data_(data),
      batches_(std::move(batches)),
      seed_(seed),
      epoch_(epoch),
      capacity_(capacity),
      num_batches_(static_cast<int>(batches_.size())) {
  STEREODET_CHECK(capacity >= 1) << "capacity must be >= 1, got " << capacity;
  for (const std::vector<int>& batch : batches_) {
    STEREODET_CHECK(!batch.empty()) << "an empty batch";
  }
  thread_ = std::thread(&BatchLoader::Produce, this);
}

BatchLoader::~BatchLoader() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void BatchLoader::Produce() {
  try {
    for (int b = 0; b < num_batches_; ++b) {
      const std::vector<int>& indices = batches_[b];
      std::vector<uint64_t> seeds;
      for (int index : indices) seeds.push_back(SampleSeed(seed_, epoch_, index));
      TrainBatch batch = data_.MakeBatch(indices, seeds);
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || static_cast<int>(queue_.size()) < capacity_; });
      if (stop_) return;
      queue_.push_back(std::move(batch));
      changed_.notify_all();
    }
  } catch (...) {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = std::current_exception();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
  changed_.notify_all();
}

std::optional<TrainBatch> BatchLoader::Next() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return !queue_.empty() || finished_; });
  if (!queue_.empty()) {
    TrainBatch batch = std::move(queue_.front());
    queue_.pop_front();
    changed_.notify_all();
    return batch;
  }
  if (error_) std::rethrow_exception(error_);
  return std::nullopt;
}

}  // namespace stereodet
