#include "stereodet/models/train_data.h"

#include <algorithm>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "stereodet/util/check.h"

namespace stereodet {

void AugmentOptions::Check() const {
  STEREODET_CHECK(flip_probability >= 0.0 && flip_probability <= 1.0)
      << "flip_probability must be in [0, 1], got " << flip_probability;
  STEREODET_CHECK(min_zoom > 0.0 && min_zoom <= max_zoom && max_zoom <= 10.0)
      << "need 0 < min_zoom <= max_zoom <= 10, got " << min_zoom << ", " << max_zoom;
  STEREODET_CHECK(brightness >= 0.0 && brightness <= 1.0)
      << "brightness must be in [0, 1], got " << brightness;
  STEREODET_CHECK(contrast >= 0.0 && contrast < 1.0)
      << "contrast must be in [0, 1), got " << contrast;
  STEREODET_CHECK(saturation >= 0.0 && saturation < 1.0)
      << "saturation must be in [0, 1), got " << saturation;
  STEREODET_CHECK(min_visible_fraction >= 0.0 && min_visible_fraction <= 1.0)
      << "min_visible_fraction must be in [0, 1], got " << min_visible_fraction;
}

void LabelTargetOptions::Check() const {
  STEREODET_CHECK(min_object_height_px >= 0.0)
      << "min_object_height_px must be >= 0, got " << min_object_height_px;
}

std::vector<TargetBox> TargetsFromLabels(const std::vector<Object>& labels,
                                         const std::vector<std::string>& classes,
                                         const LabelTargetOptions& options) {
  const std::vector<std::string>& ignore_types = options.ignore_types;
  std::vector<TargetBox> targets;
  for (const Object& label : labels) {
    const auto cls = std::find(classes.begin(), classes.end(), label.type);
    if (cls != classes.end()) {
      const bool too_small = label.box.Height() < options.min_object_height_px;
      targets.push_back({label.box, too_small ? kIgnoreLabel : 1 + (cls - classes.begin())});
    } else if (std::find(ignore_types.begin(), ignore_types.end(), label.type) !=
               ignore_types.end()) {
      targets.push_back({label.box, kIgnoreLabel});
    }
  }
  return targets;
}

// Brightness, contrast and saturation on an 8-bit BGR image.
void JitterColour(cv::Mat& bgr, const AugmentOptions& options, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double offset = unit(rng) * options.brightness * 255.0;
  const double contrast = 1.0 + unit(rng) * options.contrast;
  const double saturation = 1.0 + unit(rng) * options.saturation;
  cv::Mat f;
  bgr.convertTo(f, CV_32FC3);
  const cv::Scalar channel_means = cv::mean(f);
  const double mean = (channel_means[0] + channel_means[1] + channel_means[2]) / 3.0;
  f = (f - cv::Scalar::all(mean)) * contrast + cv::Scalar::all(mean + offset);
  cv::Mat grey, grey3;
  cv::cvtColor(f, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, grey3, cv::COLOR_GRAY2BGR);
  f = grey3 + (f - grey3) * saturation;
  f.convertTo(bgr, CV_8UC3);  // saturates to [0, 255]
}

uint64_t SampleSeed(uint64_t seed, int epoch, int frame_index) {
  // SplitMix64 over the three numbers: well mixed, cheap, and stable across platforms.
  auto mix = [](uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  return mix(mix(mix(seed) ^ static_cast<uint64_t>(epoch)) ^ static_cast<uint64_t>(frame_index));
}

std::vector<int> EpochOrder(int n, uint64_t seed, int epoch) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  // Fisher-Yates with our own index draws: std::shuffle's algorithm is not specified, so results
  // would differ between standard libraries.
  std::mt19937_64 rng(SampleSeed(seed, epoch, -1));
  for (int i = n - 1; i > 0; --i) {
    const int j = static_cast<int>(rng() % static_cast<uint64_t>(i + 1));
    std::swap(order[i], order[j]);
  }
  return order;
}

}  // namespace stereodet
