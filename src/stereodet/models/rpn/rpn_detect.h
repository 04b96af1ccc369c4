// Running a trained two-stage detector over a KITTI-format split: `stereodet detect rpn`. Writes
// one KITTI detection file per frame (OUT/ID.txt: the 2D box in the original image, the score, a
// softmax probability in [0, 1], 3D fields "not estimated") and OUT/run.json; OUT is a StagedFolder
// (one run, swapped in whole at the end), as `detect ssd` writes it.
#ifndef STEREODET_MODELS_RPN_RPN_DETECT_H_
#define STEREODET_MODELS_RPN_RPN_DETECT_H_

#include <cstdint>
#include <filesystem>
#include <string>

#include "stereodet/models/detect_shard.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/shard.h"

namespace stereodet {

struct DetectRpnOptions {
  std::filesystem::path model_dir;  // written by `stereodet train rpn`
  std::filesystem::path data_root;  // KITTI layout
  std::string subset = "training";
  std::string split = "val";
  std::filesystem::path out_dir;
  // Gaussian blur (sigma in original image px) of the network's image only; stereo matching sees
  // the sharp pair (as `detect ssd`). 0 = off.
  double blur_sigma_px = 0.0;
  int batch_size = 4;
  int threads = 0;  // LibTorch and the per-frame preparation (0 = all cores)
  int max_frames = 0;
  // Only shard K/N of those frames (after max_frames), in whole batches (detect_shard.h); 1/1 =
  // all. A shard's folder also holds detect_shard.json, for `detect merge`.
  Shard shard;
  std::string device = "cpu";
  RpnDetectOptions detect;  // 600 -> 100 proposals, score >= 0.01, class NMS 0.45, <= 100 boxes
  ProgressOptions progress;
  std::string command_line;
  // A score calibration file (`stereodet calibrate --fit`, kitti/score_calibration.h): every
  // detection of a calibrated class is written with its calibrated probability (after the score
  // threshold, which applies to the raw scores). Empty: the raw scores.
  std::filesystem::path calibration;
  void Check() const;  // throws std::invalid_argument
};

// Throws before any work as DetectSsd does (an output overlapping the data or the model, a
// non-empty folder that is not an earlier detection folder).
DetectSummary DetectRpn(const DetectRpnOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_DETECT_H_
