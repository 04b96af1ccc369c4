#include "stereodet/kitti/dataset_summary.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <system_error>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/file_checks.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace fs = std::filesystem;

void DatasetSummaryOptions::Check() const {
  STEREODET_CHECK(distance_bin_m > 0 && std::isfinite(distance_bin_m))
      << "distance_bin_m must be a positive number, got " << distance_bin_m;
}

const char* DifficultyBucketName(DifficultyBucket bucket) {
  switch (bucket) {
    case DifficultyBucket::kEasy:
      return "easy";
    case DifficultyBucket::kModerateOnly:
      return "moderate_only";
    case DifficultyBucket::kHardOnly:
      return "hard_only";
    case DifficultyBucket::kNone:
      return "none";
  }
  return "?";
}

std::optional<DifficultyBucket> ParseDifficultyBucket(std::string_view text) {
  for (int i = 0; i < kNumDifficultyBuckets; ++i) {
    const auto bucket = static_cast<DifficultyBucket>(i);
    if (text == DifficultyBucketName(bucket)) return bucket;
  }
  return std::nullopt;
}

namespace {

DifficultyBucket BucketOf(const Object& label) {
  const std::optional<Difficulty> easiest = EasiestDifficulty(label);
  if (!easiest) return DifficultyBucket::kNone;
  return static_cast<DifficultyBucket>(static_cast<int>(*easiest));
}

void AddToHistogram(std::vector<int64_t>* histogram, size_t bin) {
  if (histogram->size() <= bin) histogram->resize(bin + 1, 0);
  ++(*histogram)[bin];
}

// Bins beyond this are lumped into the last one: a label 1e300 m away must not allocate 1e299 bins.
constexpr size_t kMaxBins = 1000;

}  // namespace

DatasetSummary SummarizeDataset(const KittiDataset& dataset, std::vector<std::string> ids,
                                const DatasetSummaryOptions& options) {
  options.Check();
  DatasetSummary summary;
  summary.subset_dir = dataset.SubsetDir().string();
  summary.distance_bin_m = options.distance_bin_m;
  if (ids.empty()) ids = dataset.ListIds();
  summary.frames = static_cast<int64_t>(ids.size());

  const fs::path subset_dir = dataset.SubsetDir();
  std::error_code ec;
  auto has_folder = [&](const char* name) { return fs::is_directory(subset_dir / name, ec); };
  RequiredFiles required;
  required.calib = true;
  required.label = dataset.subset() == "training" || has_folder("label_2");
  required.image_left = has_folder("image_2");
  required.image_right = has_folder("image_3");
  required.velodyne = has_folder("velodyne");
  summary.missing_files = FindMissingFiles(dataset, ids, required);

  ObjectParseOptions parse_options;
  parse_options.kind = ObjectFileKind::kLabel;
  parse_options.lenient = options.lenient;
  ProgressReporter progress("info", static_cast<int64_t>(ids.size()), options.progress);
  for (const std::string& id : ids) {
    const FramePaths paths = dataset.Paths(id);
    // Missing files were listed above; reading only what exists keeps each problem reported once.
    if (required.label && fs::exists(paths.label, ec)) {
      try {
        ObjectFile file = ReadObjects(paths.label, parse_options);
        ++summary.frames_with_labels;
        summary.skipped_lines += file.skipped_lines;
        for (std::string& problem : file.problems) summary.skipped.push_back(std::move(problem));
        for (const Object& label : file.objects) {
          ++summary.objects;
          ClassCounts& counts = summary.classes[label.type];
          ++counts.objects;
          ++counts.by_difficulty[static_cast<int>(BucketOf(label))];
          if (label.IsDontCare()) continue;
          if (!label.Has3D()) {
            ++summary.objects_without_3d;
            continue;
          }
          const double distance_m = std::hypot(label.box3d.location.x(), label.box3d.location.z());
          const double bin = std::floor(distance_m / options.distance_bin_m);
          const size_t index =
              bin < static_cast<double>(kMaxBins) ? static_cast<size_t>(bin) : kMaxBins - 1;
          AddToHistogram(&summary.distance_histogram, index);
          AddToHistogram(&counts.distance_histogram, index);
        }
      } catch (const std::exception& e) {  // ParseError, or a file we could not read
        summary.bad_files.push_back(e.what());
      }
    }
    if (fs::exists(paths.calib, ec)) {
      try {
        const Calibration calib = ReadCalibration(paths.calib);
        const double focal_px = calib.FocalPx();
        const double baseline_m = calib.BaselineM();
        if (summary.frames_with_calib == 0) {
          summary.min_focal_px = summary.max_focal_px = focal_px;
          summary.min_baseline_m = summary.max_baseline_m = baseline_m;
        } else {
          summary.min_focal_px = std::min(summary.min_focal_px, focal_px);
          summary.max_focal_px = std::max(summary.max_focal_px, focal_px);
          summary.min_baseline_m = std::min(summary.min_baseline_m, baseline_m);
          summary.max_baseline_m = std::max(summary.max_baseline_m, baseline_m);
        }
        ++summary.frames_with_calib;
      } catch (const std::exception& e) {
        summary.bad_files.push_back(e.what());
      }
    }
    // The binary files are checked without decoding (see file_checks.h): zero-byte and truncated
    // images and scans of a wrong size are problems, not "none".
    auto check = [&](bool wanted, const fs::path& path, void (*check_file)(const fs::path&)) {
      if (!wanted || !fs::exists(path, ec)) return;
      try {
        check_file(path);
      } catch (const std::exception& e) {
        summary.bad_files.push_back(e.what());
      }
    };
    check(required.image_left, paths.image_left, CheckPngFile);
    check(required.image_right, paths.image_right, CheckPngFile);
    check(required.velodyne, paths.velodyne, CheckVelodyneFile);
    progress.Add(1);
  }
  progress.Finish();
  return summary;
}

}  // namespace stereodet
