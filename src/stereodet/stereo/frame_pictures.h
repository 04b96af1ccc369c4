// Pictures of one frame's stereo for a person to look at: `stereodet stereo frame` is this call.
#ifndef STEREODET_STEREO_FRAME_PICTURES_H_
#define STEREODET_STEREO_FRAME_PICTURES_H_

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

struct FramePicturesResult {
  // OUT/ID_disparity.png, OUT/ID_depth.png, OUT/ID_height.png (colourized, black = no stereo) and
  // OUT/ID_bev.png (the point cloud from above, 80 x 80 m), in this order.
  std::vector<std::filesystem::path> files;
  // The same four pictures for a reader: OUT/ID_disparity_key.png, ..._depth_key, ..._height_key,
  // ..._bev_key: the picture unchanged, and below it a caption and a colour bar in its units
  // (disparity px, depth m, height above ground m, velo z m; WithColourBar), in this order.
  std::vector<std::filesystem::path> keyed_files;
  int64_t stereo_pixels = 0;  // pixels with a valid height code (stereo and inside the code range)
  int64_t total_pixels = 0;   // pixels of the image
  int64_t points = 0;         // points of the stereo point cloud
  GroundPlaneFit ground;      // the frame's ground plane
};

// Encodes frame `id` of `dataset` with `options` and writes its pictures into `out` (created; each
// file atomically): disparity over [0, num_disparities] px, depth, height over the height code's
// range, and the bird's-eye view. Throws std::invalid_argument for bad options, and
// std::runtime_error naming the file for a missing or unreadable image or calibration.
FramePicturesResult WriteFramePictures(const KittiDataset& dataset, const std::string& id,
                                       const std::filesystem::path& out,
                                       const StereoOptions& options);

}  // namespace stereodet

#endif  // STEREODET_STEREO_FRAME_PICTURES_H_
