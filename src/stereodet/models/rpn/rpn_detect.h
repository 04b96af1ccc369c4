// Running a trained two-stage detector over a KITTI-format split: `stereodet detect rpn`. Writes
// one KITTI detection file per frame (OUT/ID.txt: the 2D box in the original image, the score, a
// softmax probability in [0, 1], 3D fields "not estimated") and OUT/run.json; OUT is a StagedFolder
// (one run, swapped in whole at the end), as `detect ssd` writes it.
#ifndef STEREODET_MODELS_RPN_RPN_DETECT_H_
#define STEREODET_MODELS_RPN_RPN_DETECT_H_

#include "stereodet/models/detect_shard.h"
#include "stereodet/models/rpn/rpn_model.h"

namespace stereodet {

// The run's model, data, output, batch (4 frames), threads, shard, device and calibration
// (detect_shard.h), and the two-stage detector's own settings.
struct DetectRpnOptions : DetectionRunOptions {
  DetectRpnOptions() : DetectionRunOptions(/*default_batch_size=*/4) {}

  // Gaussian blur (sigma in original image px) of the network's image only; stereo matching sees
  // the sharp pair (as `detect ssd`). 0 = off.
  double blur_sigma_px = 0.0;
  RpnDetectOptions detect;  // 600 -> 100 proposals, score >= 0.01, class NMS 0.45, <= 100 boxes
  void Check() const;       // throws std::invalid_argument
};

// Throws before any work as DetectSsd does (an output overlapping the data or the model, a
// non-empty folder that is not an earlier detection folder).
DetectSummary DetectRpn(const DetectRpnOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_DETECT_H_
