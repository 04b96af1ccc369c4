// Running a trained 3D detector over a KITTI-format split: `stereodet detect det3d`. Writes one
// KITTI detection file per frame (OUT/ID.txt: type, truncated -1, occluded -1, alpha, the 2D box
// of the projected 3D box, dimensions, location, rotation_y, score in [0, 1]) and OUT/run.json;
// OUT is a StagedFolder (one run, swapped in whole at the end), as `detect ssd` writes it; with a
// shard K/N it is the shard's folder (models/detect_shard.h).
#ifndef STEREODET_MODELS_DET3D_DET3D_DETECT_H_
#define STEREODET_MODELS_DET3D_DET3D_DETECT_H_

#include <filesystem>

#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/detect_shard.h"

namespace stereodet {

// The run's model, data, output, batch (1 frame), threads, shard, device and calibration
// (detect_shard.h), and the 3D detector's own settings.
struct DetectDet3dOptions : DetectionRunOptions {
  DetectDet3dOptions() : DetectionRunOptions(/*default_batch_size=*/1) {}

  std::filesystem::path points_dir;  // stereo models: the `stereo --encode points` folder
  Det3dDecodeOptions decode;         // score >= 0.1, BEV NMS 0.1, at most 100 boxes a frame
  PointFilterOptions filter;         // as in training (LiDAR: the camera's view; stereo: 50 m)
  void Check() const;                // throws std::invalid_argument
};

DetectSummary DetectDet3d(const DetectDet3dOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_DETECT_H_
