// Training the 3D detector on a KITTI-format split: `stereodet train det3d --input lidar|stereo`.
// The families' one loop and model folder (trainer.h, train_common.h): frames in a seeded order per
// epoch, AdamW with warm-up and cosine decay, a progress line, then (atomically) the model, the
// checkpoint, the CSV log and run.json after every epoch. The data order and the augmentation
// depend only on (seed, epoch, frame), so --resume ends with the same weights as an uninterrupted
// run (same threads, same device).
#ifndef STEREODET_MODELS_DET3D_DET3D_TRAIN_H_
#define STEREODET_MODELS_DET3D_DET3D_TRAIN_H_

#include <cstdint>
#include <filesystem>
#include <string>

#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/det3d/gt_database.h"
#include "stereodet/models/trainer.h"
#include "stereodet/util/progress.h"

namespace stereodet {

struct TrainDet3dOptions {
  std::filesystem::path data_root;   // KITTI layout: training/{calib,label_2,image_2,velodyne}
  std::filesystem::path points_dir;  // stereo input: the `stereo --encode points` folder
  std::string split = "train";
  std::filesystem::path out_dir;  // the model folder
  Det3dConfig model;              // input, classes, grid, width
  int epochs = 20;
  int batch_size = 4;
  double learning_rate = 2e-3;  // peak (AdamW)
  int warmup_steps = 50;
  double final_lr_fraction = 0.05;
  double weight_decay = 1e-2;
  uint64_t seed = 1;
  bool resume = false;
  bool force = false;  // train over a model already in out_dir
  std::string command_line;
  int threads = 0;              // LibTorch threads (0 = all cores)
  int max_frames = 0;           // only the first N frames of the split (0 = all)
  int max_epochs_this_run = 0;  // stop after N epochs in this call (0 = all); --resume continues
  int max_aux_points = 4096;    // points per frame the auxiliary network sees
  std::string device = "cpu";   // cpu | cuda
  // Data-parallel training over several processes (distributed.h); one process by default.
  DistributedOptions distributed;
  PointFilterOptions filter;
  Det3dAugmentOptions augment;
  // GT-database cut-and-paste (gt_database.h), before `augment`'s per-object and global steps;
  // only with augment.enabled. The database is built from the loaded training frames.
  GtDatabaseOptions gt_database;
  GtSamplingOptions gt_sampling;
  Det3dLossOptions loss;
  ProgressOptions progress;
  void Check() const;  // throws std::invalid_argument
};

struct TrainDet3dSummary : TrainingRunSummary {
  int objects = 0;                  // ground-truth boxes of the model's classes over the frames
  int64_t gt_database_objects = 0;  // objects in the GT database (0 without GT sampling)
  int64_t gt_database_points = 0;   // their points (16 bytes each in memory)
  int64_t auxiliary_parameters = 0;
};

TrainDet3dSummary TrainDet3d(const TrainDet3dOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_DET3D_DET3D_TRAIN_H_
