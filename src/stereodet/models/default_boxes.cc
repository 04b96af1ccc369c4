#include "stereodet/models/default_boxes.h"

#include <cmath>

#include "stereodet/util/check.h"

namespace stereodet {

void DefaultBoxOptions::Check() const {
  // At most 4096 px a side: a model.json asking for more is an error, not a bad_alloc after
  // minutes of default boxes.
  STEREODET_CHECK(input_width >= 16 && input_height >= 16 && input_width <= 4096 &&
                  input_height <= 4096)
      << "input size must be in [16, 4096] px a side, got " << input_width << "x" << input_height;
  STEREODET_CHECK(num_maps >= 1 && num_maps <= 8) << "num_maps must be in [1, 8], got " << num_maps;
  STEREODET_CHECK(first_map_stride_log2 >= 0 && first_map_stride_log2 <= 6)
      << "first_map_stride_log2 must be in [0, 6], got " << first_map_stride_log2;
  STEREODET_CHECK(min_size_fraction > 0.0 && min_size_fraction <= 1.0)
      << "min_size_fraction must be in (0, 1], got " << min_size_fraction;
  STEREODET_CHECK(!aspect_ratios.empty() && aspect_ratios.size() <= 16)
      << "aspect_ratios must hold 1 to 16 ratios, got " << aspect_ratios.size();
  for (double ratio : aspect_ratios) {
    STEREODET_CHECK(ratio > 0.0 && std::isfinite(ratio))
        << "aspect ratio must be > 0, got " << ratio;
  }
}

std::vector<FeatureMapSize> FeatureMapSizes(const DefaultBoxOptions& options) {
  options.Check();
  FeatureMapSize size{options.input_width, options.input_height};
  auto halve = [](FeatureMapSize s) {
    return FeatureMapSize{(s.width + 1) / 2, (s.height + 1) / 2};
  };
  for (int i = 0; i < options.first_map_stride_log2; ++i) size = halve(size);
  std::vector<FeatureMapSize> sizes;
  for (int k = 0; k < options.num_maps; ++k) {
    sizes.push_back(size);
    size = halve(size);
  }
  return sizes;
}

std::vector<DefaultBox> GenerateDefaultBoxes(const DefaultBoxOptions& options) {
  const std::vector<FeatureMapSize> maps = FeatureMapSizes(options);
  std::vector<DefaultBox> boxes;
  double size_px = options.min_size_fraction * options.input_height;
  for (const FeatureMapSize& map : maps) {
    const double step_x = static_cast<double>(options.input_width) / map.width;
    const double step_y = static_cast<double>(options.input_height) / map.height;
    const double sizes[2] = {size_px, size_px * std::sqrt(2.0)};
    for (int y = 0; y < map.height; ++y) {
      for (int x = 0; x < map.width; ++x) {
        for (double s : sizes) {
          for (double ratio : options.aspect_ratios) {
            const double root = std::sqrt(ratio);
            boxes.push_back({static_cast<float>((x + 0.5) * step_x),
                             static_cast<float>((y + 0.5) * step_y), static_cast<float>(s * root),
                             static_cast<float>(s / root)});
          }
        }
      }
    }
    size_px *= 2.0;
  }
  return boxes;
}

}  // namespace stereodet
