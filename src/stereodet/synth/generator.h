// `stereodet synth`: whole synthetic frames and KITTI-format data sets.
//
// A frame is one sampled scene (scene_sampler.h) ray cast by the left camera, the right camera and
// the LiDAR, with its labels and ground-truth disparity. Everything random in frame i comes from
// generators seeded by (seed, i), so frames can be made in any order, on any number of threads,
// and the same seed always gives the same bytes.
#ifndef STEREODET_SYNTH_GENERATOR_H_
#define STEREODET_SYNTH_GENERATOR_H_

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/object.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/synth/camera.h"
#include "stereodet/synth/labels.h"
#include "stereodet/synth/lidar.h"
#include "stereodet/synth/scene_sampler.h"
#include "stereodet/util/progress.h"
#include "stereodet/util/shard.h"
#include "stereodet/util/timer.h"

namespace stereodet {

struct SynthOptions {
  int width = 1242;  // image size, pixels (>= 8); intrinsics follow SynthCalibration()
  int height = 375;
  bool lidar = true;  // simulate the LiDAR (false: an empty scan, for image-only uses)
  double camera_gain_jitter = 0.02;  // per-camera gain standard deviation (relative)
  SceneOptions scene;
  RenderOptions render;
  LidarOptions lidar_options;
  LabelOptions labels;
  GroundTruthDisparityOptions disparity;

  void Check() const;  // throws std::invalid_argument
  // One line naming every setting that changes a frame's bytes; a data set records it so that a
  // resumed run can refuse to mix frames made with other settings.
  std::string Fingerprint() const;
};

struct SynthFrame {
  Calibration calib;
  cv::Mat image_left;   // CV_8UC3 BGR, camera 2
  cv::Mat image_right;  // CV_8UC3 BGR, camera 3
  cv::Mat disparity;    // CV_32FC1, left-image disparity in pixels, 0 = no ground truth
  std::vector<Object> labels;
  std::vector<VeloPoint> scan;  // velo frame
  Scene scene;                  // what was rendered (for statistics and pictures)
  cv::Mat depth_left;           // CV_32FC1, depth in front of camera 2 (m), 0 = sky
  cv::Mat object_id;            // CV_32SC1, Scene::objects index per left pixel, -1 = background
  // The true ground as a x + b y + c z + d = 0 in the rect frame, normal up (b < 0): written to
  // planes/NNNNNN.txt so that a ground-plane fit can be checked against it.
  Eigen::Vector4d ground_plane = Eigen::Vector4d(0.0, -1.0, 0.0, 1.65);
};

// Makes frame `index` of the data set with `seed`. `times` (optional) receives per-stage times.
SynthFrame GenerateFrame(const SynthOptions& options, uint64_t seed, int index,
                         StageTimes* times = nullptr);

struct DatasetOptions {
  std::filesystem::path out;  // data set root (created)
  int frames = 10;            // frames 000000 .. frames-1
  uint64_t seed = 0;
  double val_fraction = 0.5;  // share of frames listed in ImageSets/val.txt, the rest in train.txt
  int threads = 0;            // 0 = all cores
  int png_compression = 1;    // zlib level 0..9 for the PNGs (1: fast; output is deterministic)
  ProgressOptions progress;
  SynthOptions synth;
  // Make only this shard's frames (util/shard.h: a contiguous range of 0 .. frames-1); the splits
  // and synth_settings.txt are those of the whole data set, so N shards writing into one folder
  // (at once or one after another) leave exactly the folder of one run.
  Shard shard;

  void Check() const;  // throws std::invalid_argument
};

struct DatasetSummaryLine {
  int generated = 0;  // frames made in this run
  int skipped = 0;    // frames whose files were all there already (resumed)
  int train = 0, val = 0;
  int64_t objects = 0;  // labels written in this run, DontCare included
  double seconds = 0.0;
  std::string stage_times;  // StageTimes::Format() of this run
};

// Writes the data set: training/{image_2,image_3,label_2,calib,velodyne,disp_noc_0,planes}/NNNNNN.*
// and ImageSets/{train,val,trainval}.txt. Every file is written atomically; frames whose seven
// files all exist are skipped, so an interrupted run resumes where it stopped.
// ROOT/synth_settings.txt records the seed and settings; resuming with different ones throws
// std::invalid_argument. With options.shard, only that shard's frames are made (generated +
// skipped = the shard's size); the split files still list all `frames`.
DatasetSummaryLine GenerateDataset(const DatasetOptions& options);

// The frame ids in the val split: round(frames * val_fraction) of them, chosen by a hash of
// (seed, index), in increasing order. The others form the train split.
std::vector<int> ValFrames(int frames, double val_fraction, uint64_t seed);

}  // namespace stereodet

#endif  // STEREODET_SYNTH_GENERATOR_H_
