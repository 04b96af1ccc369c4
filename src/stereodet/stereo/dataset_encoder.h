// A whole KITTI-format dataset turned into the stereo inputs the detectors read: `stereodet stereo`
// is this one call.
//
//   const KittiDataset dataset("data/kitti", "training");
//   EncodeDatasetOptions options;
//   options.outputs.points = true;
//   const EncodeDatasetResult result = EncodeDataset(dataset, dataset.ReadSplit("val"), "out",
//                                                    options);
//
// Per frame ID it writes under OUT (each file atomically):
//   rgbh/ID.png        the packed RGB-H image (outputs.rgbh)
//   depth/ID.png, height/ID.png   the RGB-D depth and height codes (outputs.rgbd), and
//   image_2/ID.png     the blurred image the network sees, with outputs.rgbd and a blur
//   velodyne/ID.bin    the stereo point cloud in KITTI's velodyne format (outputs.points)
//   disparity/ID.png   KITTI-format disparity (outputs.disparity)
//   ground/ID.txt      the ground plane (always; written last, so it marks the frame done)
// and OUT/ground_summary.json, every frame's ground fit (tilt, camera height, inliers and their
// share, suspect beyond the tolerance of GroundPlaneOptions) with a summary,
// and OUT/stereo.json, the manifest of every setting that changes those bytes (DatasetManifest),
// and OUT/run.json (util/run_manifest.h: version, command line, the data folder, every frame with
// the hash of the settings and data that produced it); with evaluate, OUT/disparity_evaluation.json
// (DisparityEvaluationJson: KITTI's D1-all, the estimated-only D1 and the density, per frame and
// pooled).
// Resumable: ground/ID.txt, written last, records the frame's settings hash ("settings HASH"), and
// a frame is done only when its files are all there and that hash is this run's; other frames are
// redone (so an interrupted --force with new settings resumes correctly). A folder whose
// stereo.json records other settings, or whose run.json another --data, is refused with the
// differing settings named; other outputs ("encode") are added to the folder's, writing only the
// missing files of each frame.
#ifndef STEREODET_STEREO_DATASET_ENCODER_H_
#define STEREODET_STEREO_DATASET_ENCODER_H_

#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stereodet/kitti/dataset.h"
#include "stereodet/stereo/disparity.h"
#include "stereodet/stereo/reprojection.h"
#include "stereodet/stereo/stereo_encoder.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/shard.h"

namespace stereodet {

// Which files EncodeDataset writes per frame besides ground/ID.txt (see the header comment).
struct DatasetOutputs {
  bool rgbh = true;
  bool rgbd = false;
  bool points = false;
  bool disparity = false;

  bool Any() const { return rgbh || rgbd || points || disparity; }
};

// The chosen outputs' names joined by commas, always in the order "rgbh,rgbd,points,disparity"
// (the manifest's "encode"). Empty when none is chosen.
std::string DatasetOutputsName(const DatasetOutputs& outputs);

// Parses a comma-separated list of output names (rgbh, rgbd, points, disparity), in any order,
// spaces around a name ignored. Throws std::invalid_argument naming an unknown name
// ("unknown output 'lidar' (expected rgbh, rgbd, points, disparity)"), or when the list names none.
DatasetOutputs ParseDatasetOutputs(std::string_view text);

struct EncodeDatasetOptions {
  StereoOptions stereo;    // disparity, ground plane, codes, point cloud, blur
  DatasetOutputs outputs;  // default: RGB-H only
  // Recompute every frame, accept (and rewrite) a manifest with other settings or other data, and
  // remove the output folders of outputs not chosen this time.
  bool force = false;
  // Also compare every frame's disparity with the dataset's ground truth (FramePaths::disparity,
  // disp_noc_0/ as `stereodet synth` writes it). Every frame is computed for the comparison, but
  // the files of frames already done are kept (resume holds; EncodeDatasetResult::kept).
  bool evaluate = false;
  int num_threads = 0;       // frames in parallel (0 = all cores); results do not depend on it
  ProgressOptions progress;  // the "stereo" progress line (stream nullptr: silent)
  std::string command_line;  // for OUT/run.json (empty from a library call)
  // Encode only this shard of `ids` (util/shard.h: a contiguous range). Shards of one folder may
  // run at once (docs/scale.md): each holds its own lock (.OUT.shard-K-of-N.lock, so the same
  // shard twice is refused) and merges its frames into OUT/run.json under a short lock; the
  // files are those of one run. Not with force (a forced shard would remove the others' outputs).
  Shard shard;

  // Throws std::invalid_argument for a bad stereo setting, no output chosen, num_threads < 0, a
  // bad shard or a shard with force.
  void Check() const;
};

struct EncodeDatasetResult {
  int encoded = 0;  // frames computed by this call
  int skipped = 0;  // frames whose files were all there already (resumed)
  // Of the encoded frames: those that were already done and were recomputed only for evaluate
  // (their files kept as they were). Frames written = encoded - kept.
  int kept = 0;
  // Of the encoded frames: those whose RANSAC ground fit was accepted, and for the others, the
  // fallback's reason (GroundPlaneFit::reason without its parenthesised detail) -> frames.
  int ground_fitted = 0;
  std::map<std::string, int> ground_fallbacks;
  // Of all the frames asked for (encoded or already done): those whose accepted ground fit lies
  // beyond the warning tolerance (GroundPlaneFit::suspect), in the order of `ids`. Every frame's
  // fit is in OUT/ground_summary.json (GroundSummaryJson).
  std::vector<std::string> ground_suspect;
  std::string stage_times;  // StageTimes::Format(): decode, the encoder's stages, write
  // With evaluate: the encoded frames' disparity against ground truth, pooled over pixels
  // (PoolDisparityErrors: D1-all as KITTI reports it, the estimated-only D1, the density). All
  // zero without evaluate or when no pixel was estimated. Also written to
  // OUT/disparity_evaluation.json (DisparityEvaluationJson).
  DisparityErrorStats disparity_error;
};

// The ground plane of every frame asked for, and their summary, written by every EncodeDataset.
inline constexpr const char* kGroundSummaryFile = "ground_summary.json";

// Its text (pretty JSON, trailing newline): "tolerance" (the warning thresholds of `options`),
// "summary" {frames, fitted, fallback, suspect, tilt_deg {mean, max}, camera_height_m {mean, min,
// max} over the fitted frames, the suspect frames' ids}, and "per_frame" (ID -> {fitted, suspect,
// tilt_deg, camera_height_m, inliers, samples, inlier_fraction, reason}), in the order given.
std::string GroundSummaryJson(const std::vector<std::pair<std::string, GroundPlaneFit>>& frames,
                              const GroundPlaneOptions& options);

// Reads back the line GroundFitLine writes (the plane, fitted, inliers, samples, tilt, reason;
// camera_height_m = the offset). `suspect` is recomputed from `options`' tolerance. Throws
// ParseError naming `source` for a line of another form.
GroundPlaneFit ParseGroundFitLine(const std::string& line, const std::string& source,
                                  const GroundPlaneOptions& options);

// The file EncodeDataset writes with evaluate.
inline constexpr const char* kDisparityEvaluationFile = "disparity_evaluation.json";

// Its text (pretty JSON, trailing newline): "definition" (what each figure means, with the
// thresholds of `options`), "frames", "all" (the pooled figures: d1_all, d1_estimated, density,
// bad, mean_abs_error_px and the pixel counts) and "per_frame" (ID -> the same figures), in the
// order given.
std::string DisparityEvaluationJson(
    const DisparityErrorStats& pooled,
    const std::vector<std::pair<std::string, DisparityErrorStats>>& frames,
    const DisparityErrorOptions& options);

// The text of OUT/stereo.json for these options (pretty JSON, 2 spaces, trailing newline): the
// outputs ("encode", DatasetOutputsName) and every stereo setting that changes the outputs' bytes.
// Not in it: force, evaluate, threads, progress.
std::string DatasetManifest(const EncodeDatasetOptions& options);

// The line of ground/ID.txt after its comment line, newline included: "fitted F normal NX NY NZ
// offset_m O inliers I samples S tilt_deg T reason R" (normal to 6 decimals, offset to 4, tilt to
// 3; F = 1 for a RANSAC fit, 0 for the nominal fallback).
std::string GroundFitLine(const GroundPlaneFit& fit);

// A `stereodet stereo` folder read back by the detectors (`train ssd` / `detect ssd --stereo DIR`),
// which then read its height codes instead of running the matcher.
struct StereoFolderRecord {
  std::filesystem::path dir;
  StereoOptions stereo;    // DIR/stereo.json's disparity, ground and height-code settings
  DatasetOutputs outputs;  // its "encode"
  std::string data_dir;    // the --data subset folder DIR/run.json records (empty without one)
};

// Reads DIR/stereo.json and DIR/run.json. Throws std::runtime_error naming the file when DIR holds
// no stereo.json (it is not a `stereodet stereo` folder), when its outputs hold no height codes
// (neither rgbh nor rgbd), or when its heights were matched on blurred pairs (blur.mode "both"
// with sigma_px > 0: a detector's heights come from the sharp pair); ParseError for a bad file.
StereoFolderRecord ReadStereoFolder(const std::filesystem::path& dir);

// Throws std::runtime_error when `folder`'s run.json records another data folder than `dataset`'s
// subset folder ("DIR holds heights computed from --data A (its run.json), not B").
void CheckStereoFolderData(const StereoFolderRecord& folder, const KittiDataset& dataset);

// Frame `id`'s 9-bit height codes (CV_16UC1 at the images' resolution, 0 = no stereo) as
// EncodeDataset wrote them: DIR/height/ID.png when present (rgbd), else unpacked from
// DIR/rgbh/ID.png (exact: PackRgbh keeps all 9 bits). Throws std::runtime_error naming the file
// when the frame is not done (no DIR/ground/ID.txt, written last) or its image is missing or bad.
cv::Mat ReadStereoFolderHeight(const StereoFolderRecord& folder, const std::string& id);

// The height codes of frame `id` at the folder's match size (DisparityOptions::MatchSize of the
// image's size): exactly those StereoEncoder::Encode gives with StereoOutputs::full_resolution
// false, which a detector that matches in line feeds its network. The folder's full-resolution
// codes were upsampled from them by nearest-exact interpolation, which puts each match-size pixel
// centre inside the block it was copied to, so sampling them back at those centres recovers them
// exactly (`HeightCodesAtMatchSize`). With match_scale 1 this is ReadStereoFolderHeight.
cv::Mat ReadStereoFolderHeightAtMatchScale(const StereoFolderRecord& folder, const std::string& id);

// Nearest-exact samples of full-resolution height (or depth) codes at the pixel centres of
// `match_size`: the inverse of the encoder's upsampling (see above). Requires match_size no larger
// than the codes' size.
cv::Mat HeightCodesAtMatchSize(const cv::Mat& full_codes, cv::Size match_size);

// Encodes the frames `ids` of `dataset` into `out` (created), in parallel. Checks options first,
// then that `ids` is not empty and that every frame has both images and a calibration, that `out`
// does not overlap the dataset's subset folder or ImageSets/ (std::invalid_argument), then the
// manifests: if OUT/stereo.json records other settings (besides "encode") or OUT/run.json other
// data it throws std::runtime_error naming the file and the settings (unless force). While it
// runs it holds OutputLock(out): a second run into the same folder is refused. Throws
// std::runtime_error naming the file for an unreadable input, and with evaluate for a frame without
// ground-truth disparity. An interrupted call leaves only whole files; the next one resumes.
EncodeDatasetResult EncodeDataset(const KittiDataset& dataset, const std::vector<std::string>& ids,
                                  const std::filesystem::path& out,
                                  const EncodeDatasetOptions& options);

}  // namespace stereodet

#endif  // STEREODET_STEREO_DATASET_ENCODER_H_
