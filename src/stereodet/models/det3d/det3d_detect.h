// Running a trained 3D detector over a KITTI-format split: `stereodet detect det3d`. Writes one
// KITTI detection file per frame (OUT/ID.txt: type, truncated -1, occluded -1, alpha, the 2D box
// of the projected 3D box, dimensions, location, rotation_y, score in [0, 1]) and OUT/run.json;
// OUT is a StagedFolder (one run, swapped in whole at the end), as `detect ssd` writes it; with a
// shard K/N it is the shard's folder (models/detect_shard.h).
#ifndef STEREODET_MODELS_DET3D_DET3D_DETECT_H_
#define STEREODET_MODELS_DET3D_DET3D_DETECT_H_

#include <cstdint>
#include <filesystem>
#include <string>

#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/shard.h"

namespace stereodet {

struct DetectDet3dOptions {
  std::filesystem::path model_dir;
  std::filesystem::path data_root;
  std::filesystem::path points_dir;  // stereo models: the `stereo --encode points` folder
  std::string subset = "training";
  std::string split = "val";
  std::filesystem::path out_dir;
  int batch_size = 1;
  int threads = 0;
  int max_frames = 0;
  // Only shard K/N of those frames (after max_frames), in whole batches (detect_shard.h); 1/1 =
  // all. A shard's folder also holds detect_shard.json, for `detect merge`.
  Shard shard;
  std::string device = "cpu";
  Det3dDecodeOptions decode;  // score >= 0.1, BEV NMS 0.1, at most 100 boxes a frame
  PointFilterOptions filter;  // as in training (LiDAR: the camera's view; stereo: 50 m)
  ProgressOptions progress;
  std::string command_line;
  // A score calibration file (`stereodet calibrate --fit`, kitti/score_calibration.h): every
  // detection of a calibrated class is written with its calibrated probability (after the score
  // threshold, which applies to the raw scores). Empty: the raw scores.
  std::filesystem::path calibration;
  void Check() const;
};

DetectSummary DetectDet3d(const DetectDet3dOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_DETECT_H_
