// Where `stereodet run` reads its stereo pairs from, one at a time, in order: a KITTI split, two
// image sequences, a stereo video (side by side, or two synchronized files) or a camera. Every
// source gives decoded frames (8-bit BGR, left and right of one size) with an index, an id and a
// timestamp; what a frame lacks (a file that is missing or does not decode, a right image of
// another size) is said in its `error`, and the stream goes on.
#ifndef STEREODET_REALTIME_FRAME_SOURCE_H_
#define STEREODET_REALTIME_FRAME_SOURCE_H_

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "stereodet/models/detector.h"

namespace stereodet {

// One stereo pair as the source gave it, before any detection.
struct SourceFrame {
  int64_t index = 0;    // 0-based position in the source
  double read_s = 0.0;  // seconds spent reading and decoding it
  StereoFrame frame;    // id, timestamp_s, left, right, calib, points (what was asked for)
  std::string error;    // why the frame is not usable ("" = it is); the stream goes on
};

struct FrameSourceOptions {
  // Exactly one source:
  std::filesystem::path data_root;  // a KITTI layout: SUBSET/{image_2,image_3,calib,velodyne}
  std::string split = "val";        // with data_root: ImageSets/SPLIT.txt or a split file
  std::string subset = "training";  // with data_root
  std::string left, right;          // image sequences: folders (their .png/.jpg files) or globs
  std::filesystem::path video;      // one stereo video: left half | right half of each frame
  std::filesystem::path left_video, right_video;  // two synchronized videos
  int camera = -1;  // a camera index (side by side, as `video`); -1 = none

  // The calibration of every frame of a non-KITTI source (a KITTI calib file: P2, P3, ...).
  std::filesystem::path calib;
  // The source's frame rate: the timestamps of image sequences (KITTI's 10 Hz by default), and the
  // pace of --realtime. 0 for a video or camera = the rate it reports.
  double fps = 0.0;
  int max_frames = 0;  // stop after this many frames (0 = all)
  // Read and decode every frame before the first is given (a finite source only): the stream then
  // times detection alone, without file reading or PNG decoding (benchmarks). Each frame's `read_s`
  // is then 0. Every frame is held in memory at once (about 2.8 MB a 1242 x 375 pair).
  bool preload = false;
  // What to read of each frame (Detector::needs(): the right image and the calibration for stereo
  // models, the LiDAR scan for a LiDAR 3D model; a KITTI source only has scans).
  DetectorNeeds needs;

  // Throws std::invalid_argument naming the flags when none or several sources are given, or one
  // is incomplete (a right sequence without a left one, a non-KITTI source without --calib when
  // `needs` asks for it, a LiDAR model with a source that has no scans).
  void Check() const;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The next frame, or nullopt after the last (or when the source ends early: a video whose
  // second file runs out, a camera that stops). Not thread-safe: one reader.
  virtual std::optional<SourceFrame> Next() = 0;
  // Frames per second the source plays at (--realtime's pace, the timestamps of sequences).
  virtual double fps() const = 0;
  // The number of frames when known (a split, a sequence, a video's frame count), else -1.
  virtual int64_t size() const { return -1; }
  // One line that names the source ("KITTI data/synth, split val (1000 frames)").
  virtual std::string Describe() const = 0;
};

// Opens the source `options` names. Throws std::invalid_argument for bad options,
// std::runtime_error naming the file for a source that cannot be opened (a missing folder, a video
// OpenCV cannot read, no frame files), and, before the first frame, for a calibration that does
// not fit the images (its principal point outside the first frame's image).
std::unique_ptr<FrameSource> OpenFrameSource(const FrameSourceOptions& options);

// The files of an image sequence, sorted by name: a folder's .png, .jpg and .jpeg files, or the
// files a glob pattern ("cam/left_*.png") matches. Throws std::runtime_error naming the pattern
// when there is none.
std::vector<std::filesystem::path> SequenceFiles(const std::string& folder_or_glob);

}  // namespace stereodet

#endif  // STEREODET_REALTIME_FRAME_SOURCE_H_
