// Training the two-stage detector on a KITTI-format split: `stereodet train rpn --input rgb|rgbd`.
// The families' one loop and model folder (trainer.h, train_common.h): frames in a seeded order per
// epoch, AdamW with a linear warm-up and a cosine decay, a progress line, then (atomically) the
// model, the checkpoint, the CSV log and run.json after every epoch.
//
// Determinism (bit-identical --resume): a step's batch is made in order in this thread (samples in
// parallel, each into its own slot, from SampleSeed(seed, epoch, frame)); the anchor and RoI
// sampling draw from a seed of (seed, step), and torch::manual_seed is set to it before every
// step; LibTorch's threads are fixed by --threads for the whole run. So a resumed run ends with the
// same weights as an uninterrupted one on the same device and thread count (on the CPU; CUDA's
// grid_sample backward adds with atomics, so GPU runs are close, not bit-identical).
#ifndef STEREODET_MODELS_RPN_RPN_TRAIN_H_
#define STEREODET_MODELS_RPN_RPN_TRAIN_H_

#include <cstdint>
#include <filesystem>
#include <string>

#include "stereodet/models/rpn/rpn_data.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/models/trainer.h"
#include "stereodet/util/progress.h"

namespace stereodet {

struct TrainRpnOptions {
  std::filesystem::path data_root;  // KITTI layout: training/, ImageSets/
  std::string split = "train";
  std::filesystem::path out_dir;  // the model folder (rpn_model.h)
  RpnConfig model;                // input, classes, input size, widths, anchors
  int epochs = 12;
  int batch_size = 4;
  double learning_rate = 1e-3;  // peak (AdamW)
  int warmup_steps = 100;
  double final_lr_fraction = 0.05;
  uint64_t seed = 1;
  bool resume = false;
  bool force = false;
  // "Mirroring" (the paper's pretrained weights, which cannot be downloaded here): a model folder
  // of an rgb model whose image branch, RPN and box head initialise this model (RpnModel::InitFrom)
  // before the first step; empty = random initialisation. Ignored on resume (the checkpoint has
  // the weights).
  std::filesystem::path init_from;
  bool init_geometry = false;  // also mirror the image branch into the geometry branch
  std::string command_line;
  int threads = 0;              // LibTorch threads (0 = all cores); fixed for the run
  int max_frames = 0;           // only the first N frames of the split (0 = all)
  int max_epochs_this_run = 0;  // stop after N epochs in this call (0 = all); --resume continues
  std::string device = "cpu";   // cpu | cuda
  // Data-parallel training over several processes (distributed.h); one process by default.
  DistributedOptions distributed;
  RpnDataOptions data;
  RpnTrainerOptions trainer;
  ProgressOptions progress;
  void Check() const;  // throws std::invalid_argument
};

struct TrainRpnSummary : TrainingRunSummary {
  int objects = 0;
  double stereo_seconds = 0;  // the one-off label / stereo pass
  int64_t image_branch_parameters = 0;
  int64_t geometry_branch_parameters = 0;
  int init_tensors = 0;  // tensors copied from init_from (0 without)
};

// Trains and writes out_dir/{model.json, model.pt, checkpoint.pt, train_log.csv, run.json}. With
// resume the model settings come from out_dir/model.json (a different --input is an error). Throws
// before any work as TrainSsd does (output overlapping the data, a trained model in out_dir without
// --resume or --force, an unwritable folder, another run holding its lock).
TrainRpnSummary TrainRpn(const TrainRpnOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_RPN_RPN_TRAIN_H_
