// Random KITTI-like labels and detections for tests and benchmarks: cars, pedestrians, cyclists,
// vans, sitting persons and DontCare regions on a road in front of a KITTI-like camera, and noisy
// detections of them (duplicates, misses, false positives), with consistent 2D and 3D boxes.
#ifndef STEREODET_EVAL_RANDOM_FRAMES_H_
#define STEREODET_EVAL_RANDOM_FRAMES_H_

#include <cstdint>
#include <vector>

#include "stereodet/eval/frame_data.h"

namespace stereodet {

struct RandomFramesOptions {
  int num_frames = 100;
  double labels_per_frame = 4.8;         // mean, objects (DontCare included)
  double detection_probability = 0.85;   // a label is detected at least once
  double duplicate_probability = 0.3;    // ...and a second, overlapping time
  double false_positives_per_frame = 2;  // mean, detections of nothing
  double position_noise = 0.01;          // 3D position noise, std as a fraction of the depth
  // Small scene (few metres, near the camera): dense, heavily overlapping boxes for property tests.
  bool crowded = false;
  // Scores rounded to this many decimals (KITTI files carry 2): creates ties. 0 = full precision.
  int score_decimals = 0;
  uint64_t seed = 1;
};

// Frame ids are "000000", "000001", ...
std::vector<EvalFrame> RandomFrames(const RandomFramesOptions& options);

}  // namespace stereodet

#endif  // STEREODET_EVAL_RANDOM_FRAMES_H_
