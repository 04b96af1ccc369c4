// The result files KITTI's official devkit (devkit_object, cpp/evaluate_object.cpp) writes, from
// stereodet's KITTI-matcher evaluation, so that scripts written for the devkit's output keep
// working
// (`stereodet eval --out DIR --devkit-files`, docs/metrics.md).
#ifndef STEREODET_REPORT_DEVKIT_FILES_H_
#define STEREODET_REPORT_DEVKIT_FILES_H_

#include <filesystem>
#include <vector>

#include "stereodet/eval/evaluator.h"

namespace stereodet {

// Writes into `dir`, for every class and overlap kind that `result` evaluated at all three
// difficulties (classes lower-cased, as the devkit names them: "car"):
//   stats_CLASS_detection.txt (2D), stats_CLASS_detection_ground.txt (BEV),
//   stats_CLASS_detection_3d.txt (3D): the 41 precision slots after the envelope, one line per
//     difficulty (Easy, Moderate, Hard), each value as printf's "%f " (six decimals and a space),
//     the line ended by "\n" (the devkit's saveStats);
//   stats_CLASS_orientation.txt: the same of the AOS slots, 2D only and only where AOS is computed
//     (no detection with alpha -10);
//   plot/CLASS_KIND.txt (KIND: detection, orientation, detection_ground, detection_3d): 41 lines
//     "%f %f %f %f\n" of recall i/40 and the three difficulties' slots (its saveAndPlotPlots' data;
//     the gnuplot, EPS and PDF files are not made).
// The LET kinds have no devkit file (the devkit has no LET) and are skipped. Files are written
// atomically. Returns the paths written, in that order per class and kind.
// Requires the KITTI matcher's arrays (ClassResult::kitti_precision): throws std::invalid_argument
// naming what is missing for another matcher, or when no class x kind has all three difficulties
// (a run of --difficulties moderate has nothing the devkit would write).
std::vector<std::filesystem::path> WriteDevkitFiles(const std::filesystem::path& dir,
                                                    const EvalResult& result);

}  // namespace stereodet

#endif  // STEREODET_REPORT_DEVKIT_FILES_H_
