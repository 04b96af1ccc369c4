// Tiny configurations of each detector family, for tests. Torch-free (models_core_test uses it
// without LibTorch); models_test_util.h adds the helpers that build, train and save models.
#ifndef STEREODET_MODELS_CONFIG_TEST_UTIL_H_
#define STEREODET_MODELS_CONFIG_TEST_UTIL_H_

#include "stereodet/models/det3d/det3d_config.h"
#include "stereodet/models/rpn/rpn_config.h"
#include "stereodet/models/ssd/ssd_config.h"

namespace stereodet {

// Tiny networks of each family, for tests that build, train a few steps or save a model in seconds.
// SSD: 64 x 48 px input, 8 base channels.
inline SsdConfig TinySsdConfig(InputEncoding encoding = InputEncoding::kRgb) {
  SsdConfig config;
  config.encoding = encoding;
  config.boxes.input_width = 64;
  config.boxes.input_height = 48;
  config.boxes.min_size_fraction = 0.2;
  config.base_channels = 8;
  return config;
}

// Two-stage: 64 x 32 px input, one block a stage, 3 x 3 pooled regions, anchors of 16 and 32 px.
inline RpnConfig TinyRpnConfig(RpnInput input = RpnInput::kRgb) {
  RpnConfig config;
  config.input = input;
  config.input_width = 64;
  config.input_height = 32;
  config.image_width = 4;
  config.geometry_width = 4;
  config.blocks_per_stage = 1;
  config.head_channels = 16;
  config.pooled_size = 3;
  config.anchors.sizes_px = {16, 32};
  return config;
}

// 3D: a 25.6 m x 25.6 m grid (x 0 .. 25.6, y -12.8 .. 12.8), 16 base channels.
inline Det3dConfig TinyDet3dConfig() {
  Det3dConfig c;
  c.grid.min_x_m = 0;
  c.grid.max_x_m = 25.6;
  c.grid.min_y_m = -12.8;
  c.grid.max_y_m = 12.8;
  c.base_channels = 16;
  return c;
}

}  // namespace stereodet

#endif  // STEREODET_MODELS_CONFIG_TEST_UTIL_H_
