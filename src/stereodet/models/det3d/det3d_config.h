// The 3D detector's configuration (point source, classes, BEV grid, widths, PSWarp parts) and
// model.json's text of it. Torch-free: the model_json fuzzer builds it with clang.
#ifndef STEREODET_MODELS_DET3D_DET3D_CONFIG_H_
#define STEREODET_MODELS_DET3D_DET3D_CONFIG_H_

#include <string>
#include <vector>

#include "stereodet/models/det3d/det3d_data.h"
#include "stereodet/models/det3d/det3d_targets.h"
#include "stereodet/models/model_json.h"

namespace stereodet {

struct Det3dConfig {
  PointSource input = PointSource::kLidar;
  std::vector<std::string> classes = {"Car"};  // KITTI spelling; anchors from DefaultAnchorClass
  BevGridOptions grid;                         // 48 x 48 m at 0.4 m: a 120 x 120 canvas
  int base_channels = 32;                      // pillar features; blocks have 1, 2, 4 x this
  int max_points_per_pillar = 32;              // points beyond are dropped (first ones kept)
  int parts_l = 2, parts_w = 2;                // PSWarp's part grid over a box
  void Check() const;                          // throws std::invalid_argument
  static constexpr int kHeadStride = 2;        // head map cells per canvas cell
  std::vector<AnchorClass> AnchorClasses() const;
};

std::string Det3dConfigToJson(const Det3dConfig& config, const WeightsRecord& weights = {});
// Parse errors throw ParseError naming `source` and the field.
Det3dConfig Det3dConfigFromJson(const std::string& text, const std::string& source);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_CONFIG_H_
