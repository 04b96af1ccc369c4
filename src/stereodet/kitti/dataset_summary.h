// What a KITTI-format dataset holds and what is wrong with it: the numbers behind `stereodet info`.
#ifndef STEREODET_KITTI_DATASET_SUMMARY_H_
#define STEREODET_KITTI_DATASET_SUMMARY_H_

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/util/progress.h"

namespace stereodet {

struct DatasetSummaryOptions {
  // Skip bad label lines (counted in DatasetSummary::skipped_lines) instead of rejecting the file.
  bool lenient = false;
  // Width of the distance histogram's bins, metres (> 0).
  double distance_bin_m = 10.0;
  // Progress over the frames; `progress.stream = nullptr` silences it.
  ProgressOptions progress;
  // Throws std::invalid_argument for a bad setting.
  void Check() const;
};

// Per-class counts. Difficulty columns are exclusive, so they add up to `objects`: Easy, Moderate
// but not Easy, Hard but not Moderate, and none (below KITTI's Hard limits, or DontCare).
enum class DifficultyBucket { kEasy = 0, kModerateOnly = 1, kHardOnly = 2, kNone = 3 };
inline constexpr int kNumDifficultyBuckets = 4;
const char* DifficultyBucketName(DifficultyBucket bucket);  // "easy", "moderate_only", ...
std::optional<DifficultyBucket> ParseDifficultyBucket(std::string_view text);

struct ClassCounts {
  int64_t objects = 0;
  std::array<int64_t, kNumDifficultyBuckets> by_difficulty{};  // indexed by DifficultyBucket
  // Objects per distance bin (see DatasetSummary::distance_histogram), those with 3D fields only.
  std::vector<int64_t> distance_histogram;
};

struct DatasetSummary {
  std::string subset_dir;          // ROOT/SUBSET
  int64_t frames = 0;              // frames looked at (the split's, or all the subset's)
  int64_t frames_with_labels = 0;  // frames whose label file was read
  int64_t objects = 0;             // all objects read, DontCare included
  std::map<std::string, ClassCounts> classes;  // by class name, unknown names included
  // Bin i counts objects (DontCare and objects without 3D excluded) whose label distance
  // sqrt(x^2 + z^2) in the rect frame lies in [i * bin, (i + 1) * bin) metres. Trailing empty bins
  // are dropped.
  double distance_bin_m = 10.0;
  std::vector<int64_t> distance_histogram;
  int64_t objects_without_3d = 0;  // non-DontCare objects with KITTI's "not estimated" 3D fields

  // Calibration over the frames whose calib file was read (0 when none was).
  int64_t frames_with_calib = 0;
  double min_focal_px = 0, max_focal_px = 0;
  double min_baseline_m = 0, max_baseline_m = 0;

  // Problems, each one line, in frame order.
  std::vector<std::string> missing_files;  // "000042: label_2/000042.txt"
  std::vector<std::string> bad_files;      // "FILE:LINE: field F: message" (strict) or read errors
  int skipped_lines = 0;                   // lenient mode: bad label lines skipped
  std::vector<std::string> skipped;        // their "FILE:LINE: field F: message"

  // Missing files or bad files (bad lines skipped in lenient mode do not count).
  bool HasProblems() const { return !missing_files.empty() || !bad_files.empty(); }
};

// Reads the label and calib files of `ids` (all of dataset.ListIds() when empty) and counts.
// Required files: calib always; label_2 on training/ (or wherever a label_2 folder exists);
// image_2, image_3 and velodyne only where that folder exists, so a download without the scans is
// not reported as broken. Never throws for bad or missing files: they are listed as problems.
DatasetSummary SummarizeDataset(const KittiDataset& dataset, std::vector<std::string> ids,
                                const DatasetSummaryOptions& options = {});

}  // namespace stereodet

#endif  // STEREODET_KITTI_DATASET_SUMMARY_H_
