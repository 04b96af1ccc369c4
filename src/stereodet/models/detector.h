// One interface for every detector family: a trained model opened from its folder, run per frame
// (or per batch) on data held in memory. The batch commands (`detect ssd|rpn|det3d`, `detect
// --model`), the benchmarks and the tests are loops over it; nothing here reads a KITTI folder.
//
//   Detector detector = Detector::Open("models/ssd-rgbh-learned");
//   StereoFrame frame;
//   frame.left = left_bgr;  frame.right = right_bgr;  frame.calib = calib;
//   const DetectResult result = detector.Detect(frame);
//   for (const Object& o : result.objects) ...   // KITTI objects, in the left image's px
//
// The family comes from model.json ("architecture": ssd, rpn or det3d). LibTorch stays behind the
// families' .cc files: no torch type in this header.
//
// Threads: a Detector is used by one thread at a time (LibTorch parallelises inside a call, with
// DetectorOptions::threads). Prepare() is const and may run on a second thread while Run() runs on
// the first (the batch commands overlap the stereo of batch k + 1 with the network of batch k this
// way). Two Detectors on two threads are independent.
#ifndef STEREODET_MODELS_DETECTOR_H_
#define STEREODET_MODELS_DETECTOR_H_

#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/models/box_coder.h"
#include "stereodet/models/det3d/det3d_data.h"
#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/stereo/stereo_encoder.h"

namespace stereodet {

// One stereo frame in memory: what every detector family reads, each the parts it needs
// (Detector::needs()). Images are 8-bit BGR (CV_8UC3), the rectified pair of KITTI's cameras 2
// (left) and 3 (right) of equal size.
struct StereoFrame {
  std::string id;                    // names the frame in messages ("" is fine)
  double timestamp_s = 0.0;          // the source's time of the frame, s (0 when it has none)
  cv::Mat left;                      // every image model; the 3D models need its size only
  cv::Mat right;                     // models that match stereo (RGB-H, RGB-D; 3D on stereo points)
  std::optional<Calibration> calib;  // stereo and 3D models
  // Points in the velodyne frame (x, y, z m, reflectance): the LiDAR scan for a LiDAR 3D model,
  // the stereo point cloud for a stereo one. A stereo 3D model computes them from the pair when
  // absent (with DetectorOptions::stereo, else StereoOptions' defaults, those of `stereo --encode
  // points`).
  std::optional<std::vector<VeloPoint>> points;
  // RGB-H models: the height codes at the match size, as a `stereo` folder holds them
  // (ReadStereoFolderHeightAtMatchScale); computed from the pair when empty.
  cv::Mat height_code;
  // The left image's size when `left` is not given (a 3D model given points needs the size only,
  // to keep the objects that project into the image); ignored when `left` is.
  cv::Size image_size;
};

// What a family reads of a StereoFrame; a frame without it is refused naming the frame and part.
struct DetectorNeeds {
  // The images themselves (not only the left one's size). A frame that carries what the pair
  // would give needs no pair: RGB-H heights (StereoFrame::height_code; the left image still
  // needed), a stereo 3D model's points (StereoFrame::points; the left image's size suffices).
  bool left_image = false;
  bool right_image = false;
  bool calibration = false;
  bool points = false;  // a LiDAR model: the scan (a stereo 3D model computes its own)
};

struct DetectorOptions {
  std::string device = "cpu";  // cpu | cuda (device.h)
  int threads = 0;             // LibTorch and per-frame preparation threads (0 = all cores)
  // Gaussian blur (sigma in image px) of the network's image only; stereo matching sees the sharp
  // pair (the paper's degradation study). 0 = off. Image families only.
  double blur_sigma_px = 0.0;
  // RGB-H models and stereo 3D models: the stereo settings. Unset: those model.json records (what
  // the model was trained with); for a stereo 3D model StereoOptions' defaults.
  std::optional<StereoOptions> stereo;
  // Each family's decoding, used by its models only (defaults: each family's own).
  DecodeOptions ssd;                // score 0.01, NMS 0.45, at most 100 boxes a frame
  RpnDetectOptions rpn;             // proposals and the head's decoding
  Det3dDecodeOptions det3d;         // score 0.1, BEV NMS
  PointFilterOptions det3d_points;  // which points a 3D model sees (camera view, range)
  // A score calibration file (kitti/score_calibration.h, `stereodet calibrate --fit`): each
  // detection of a calibrated class gets its calibrated probability once decoded (after the
  // family's raw-score threshold). Read by Open. Empty: the network's scores.
  std::filesystem::path calibration;
  void Check() const;  // throws std::invalid_argument naming the field
};

// Wall-clock seconds of one frame's stages. For a batch, network_s is the batch's network time
// divided by its frames.
struct DetectStageTimes {
  double stereo_s = 0.0;  // matching, depth, heights, points (0 for models without stereo)
  double encode_s = 0.0;  // blur, resizing and packing the network's input
  double network_s = 0.0;
  double decode_s = 0.0;  // boxes to KITTI objects (NMS is inside the network stage for all)
  double Total() const { return stereo_s + encode_s + network_s + decode_s; }
};

struct DetectResult {
  std::string id;               // the frame's
  std::vector<Object> objects;  // KITTI objects; 2D boxes in the left image's px; score in [0, 1]
  DetectStageTimes times;
};

class Detector {
 public:
  // Reads model.json and model.pt of `model_dir` (any family) and checks them: the weights' hash,
  // shapes and finiteness. Throws std::runtime_error naming the file, std::invalid_argument for bad
  // options.
  static Detector Open(const std::filesystem::path& model_dir, const DetectorOptions& options = {});
  ~Detector();
  Detector(Detector&&) noexcept;
  Detector& operator=(Detector&&) noexcept;

  const std::filesystem::path& model_dir() const;
  const std::string& family() const;  // "ssd", "rpn" or "det3d" (model.json's architecture)
  const std::string& input() const;   // the model's input: rgb, rgbh-fixed, rgbd, lidar, ...
  const std::vector<std::string>& classes() const;
  const DetectorNeeds& needs() const;
  const DetectorOptions& options() const;
  // The stereo settings the model's stereo stage uses (empty for models without one).
  std::optional<StereoOptions> stereo() const;
  // FNV-1a 64 of the model's model.pt, 16 hex digits: the hash model.json records, which opening
  // the model checked against the bytes it loaded (for run.json's model_weights_fnv1a64, without
  // reading the weights again); hashed from model.pt for a model.json that records none.
  const std::string& weights_fnv1a64() const;

  // One frame; the same objects as the frame inside any batch of DetectBatch.
  DetectResult Detect(const StereoFrame& frame);
  // One network pass over the frames (their preparation in parallel). Results in frame order.
  std::vector<DetectResult> DetectBatch(const std::vector<StereoFrame>& frames);

  // The two halves of DetectBatch, for pipelines that overlap them: frames prepared for the
  // network (each family's inputs live in a subclass of its own), to be passed to Run().
  class PreparedBatch {
   public:
    virtual ~PreparedBatch() = default;
    size_t size() const { return results.size(); }

    const void* owner = nullptr;        // the detector that prepared it (Run refuses another's)
    std::vector<DetectResult> results;  // ids and stage times so far, one per frame
  };
  // Checks and prepares the frames for the network: stereo, encoding (thread-safe with Run()).
  // Throws std::invalid_argument naming the frame and the part it lacks, std::runtime_error for
  // frames that do not fit (a pair of two sizes, a calibration that does not fit the matcher).
  std::unique_ptr<PreparedBatch> Prepare(const std::vector<StereoFrame>& frames) const;
  // The network and the decoding. Throws std::runtime_error naming the model and the frame when
  // the network's output is not finite.
  std::vector<DetectResult> Run(std::unique_ptr<PreparedBatch> batch);

  struct Impl;  // one per family (detector.cc)

 private:
  explicit Detector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// Detector::Open for a command of one family (`detect ssd`): a model of another family is refused
// naming both and the command that runs it ("models/det3d-lidar holds a det3d model, not an ssd
// one: use `detect det3d` or `detect --model`").
Detector OpenDetectorOfFamily(const std::filesystem::path& model_dir,
                              const DetectorOptions& options, const std::string& family);

// The family a model folder holds: model.json's "architecture" ("ssd" when absent: the first
// models did not record it). Throws std::runtime_error / ParseError naming model.json.
std::string ModelFamily(const std::filesystem::path& model_dir);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DETECTOR_H_
