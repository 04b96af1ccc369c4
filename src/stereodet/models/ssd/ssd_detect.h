// Running a trained SSD over a KITTI-format split: `stereodet detect ssd`. Writes one KITTI
// detection file per frame (OUT/ID.txt, also for frames without detections), which `stereodet eval
// --det OUT` and KITTI's devkit read, and OUT/run.json (util/run_manifest.h): the model (path and
// the hash of its model.pt), the data, the settings and every frame written with its file's hash.
// OUT holds one run: it is written as a StagedFolder (a hidden sibling, swapped in at the end), so
// no detection file of an earlier run survives beside the new ones. With a shard K/N, OUT is the
// shard's folder (detect_shard.h): its frames' files, its run.json and detect_shard.json, which
// `detect merge` (MergeDetections) turns into the folder of one run.
#ifndef STEREODET_MODELS_SSD_SSD_DETECT_H_
#define STEREODET_MODELS_SSD_SSD_DETECT_H_

#include <filesystem>
#include <optional>
#include <string>

#include "stereodet/models/box_coder.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

// The run's model, data, output, batch (8 images), threads, shard (DetectSsdShardTest), device and
// calibration (detect_shard.h), and the single-shot detector's own settings.
struct DetectSsdOptions : DetectionRunOptions {
  DetectSsdOptions() : DetectionRunOptions(/*default_batch_size=*/8) {}

  // Gaussian blur (sigma in original image px) of the network's image only; stereo matching sees
  // the sharp pair, as in the paper's degradation study. 0 = off.
  double blur_sigma_px = 0.0;
  DecodeOptions decode;  // score threshold 0.01, NMS 0.45, at most 100 boxes a frame
  // Prepare the next batch (reading, stereo, encoding) on a second thread while the network runs
  // on this one (RunTwoStagePipeline). The detections are the same either way.
  bool pipeline = true;
  // Stereo pipeline for RGB-H models. Unset: the settings model.json records (what the model was
  // trained with; the defaults for a model.json written before they were recorded). Set: these,
  // even where they differ (StereoMismatch tells which; `detect ssd` warns).
  std::optional<StereoOptions> stereo;
  // RGB-H: read the height codes from this `stereodet stereo` folder (`--stereo DIR`) instead of
  // matching. Refused (std::invalid_argument naming the setting) when its stereo.json's settings
  // differ from those above (the model's, or `stereo`), and when its run.json records other data.
  std::filesystem::path stereo_dir;
  void Check() const;  // throws std::invalid_argument
};

// The stereo settings the model in `model_dir` was trained with (model.json's "stereo", the
// defaults for a model.json written before they were recorded); nullopt for an rgb model, which
// uses none. Throws std::runtime_error / ParseError naming model.json.
std::optional<StereoOptions> ModelStereoSettings(const std::filesystem::path& model_dir);

// The stereo settings `options.stereo` changes from those the RGB-H model in `options.model_dir`
// was trained with (model.json), as DifferingStereoSettings words them
// ("disparity.uniqueness_ratio: 15 (requested: 5)"); empty when unset, equal, or the model is rgb.
// Throws as ReadStereoRecord.
std::string StereoMismatch(const DetectSsdOptions& options);

// Before any work it throws std::invalid_argument when out_dir overlaps the data's subset folder,
// its ImageSets/ or the model folder, and std::runtime_error when out_dir is a non-empty folder
// without run.json (not an earlier detection folder); an earlier run's folder is replaced whole
// at the end. An interrupted call leaves the previous folder as it was.
DetectSummary DetectSsd(const DetectSsdOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_SSD_DETECT_H_
