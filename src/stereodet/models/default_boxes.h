// The SSD's default boxes ("priors"): a fixed set of boxes tiled over the multi-scale feature maps.
// The network predicts, for every default box, class scores and an offset from the box
// (box_coder.h).
//
// Frame and units: network-input pixels (x right, y down), i.e. the image after it was resized to
// the model's input size, not the original KITTI image.
#ifndef STEREODET_MODELS_DEFAULT_BOXES_H_
#define STEREODET_MODELS_DEFAULT_BOXES_H_

#include <vector>

#include "stereodet/geometry/box.h"

namespace stereodet {

// A default box by its centre and size, network-input pixels.
struct DefaultBox {
  float cx = 0, cy = 0;  // centre, px
  float w = 0, h = 0;    // size, px
  Box2D ToBox2D() const { return {cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0}; }
};

struct DefaultBoxOptions {
  int input_width = 621;   // network input, px
  int input_height = 188;  // network input, px
  // The feature maps: the first has stride 2^first_map_stride_log2 (its size is the input's halved,
  // rounding up, that many times, as a 3x3 stride-2 convolution with padding 1 does); each next map
  // halves again. Must match the backbone (ssd_net.cc): 4 maps at strides 8, 16, 32, 64.
  int num_maps = 4;
  int first_map_stride_log2 = 3;
  // Box size s = sqrt(w * h) on map k: the smallest is min_size_fraction * input_height, and each
  // map doubles it. Each cell gets the sizes s and s * sqrt(2) (between this map's and the next's).
  // 0.085 * 188 px = 16 px: KITTI's moderate minimum (25 px at full resolution) at half resolution.
  double min_size_fraction = 0.085;
  // Width / height, in pixels. Pedestrians ~0.4, cyclists ~0.6-1.2, cars 1 (rear view) to 3 (side).
  std::vector<double> aspect_ratios = {0.4, 1.0, 2.0, 3.0};

  void Check() const;  // throws std::invalid_argument
  int BoxesPerCell() const { return 2 * static_cast<int>(aspect_ratios.size()); }
};

struct FeatureMapSize {
  int width = 0, height = 0;  // cells
};

// The size of each feature map for the options' input size, in map order.
std::vector<FeatureMapSize> FeatureMapSizes(const DefaultBoxOptions& options);

// All default boxes, in the order the network's heads emit them: map by map; within a map row by
// row (y), then column (x); within a cell size by size (s, then s * sqrt(2)), then aspect ratio in
// the options' order. Centres are at ((x + 0.5) * input_width / map_width, (y + 0.5) * input_height
// / map_height).
std::vector<DefaultBox> GenerateDefaultBoxes(const DefaultBoxOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DEFAULT_BOXES_H_
