// Training an SSD on a KITTI-format split: `stereodet train ssd`.
//
// The families' one loop (trainer.h). Per epoch: frames in a seeded random order, batches built
// by a BatchLoader thread while the network trains, AdamW with a linear warm-up then a cosine decay
// of the learning rate over all steps, a progress line with the loss and images per second, then
// (atomically) the model, the checkpoint and the CSV log. --resume continues from the checkpoint's
// epoch; because the data order, the augmentation and the schedule depend only on (seed, epoch,
// step), a resumed run ends with the same weights as an uninterrupted one (same threads;
// LibTorch's CPU kernels are deterministic for a fixed thread count).
#ifndef STEREODET_MODELS_SSD_SSD_TRAIN_H_
#define STEREODET_MODELS_SSD_SSD_TRAIN_H_

#include <cstdint>
#include <filesystem>
#include <string>

#include "stereodet/models/ssd/ssd_data.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/models/trainer.h"
#include "stereodet/util/progress.h"

namespace stereodet {

struct TrainSsdOptions {
  std::filesystem::path data_root;  // KITTI layout: training/, ImageSets/
  std::string split = "train";      // ImageSets/SPLIT.txt, or a path to a split file
  std::filesystem::path out_dir;    // the model folder (ssd.h)
  SsdConfig model;                  // encoding, classes, input size, width
  int epochs = 10;                  // the committed models (docs/models.md)
  int batch_size = 8;
  double learning_rate = 2e-3;      // peak (AdamW)
  int warmup_steps = 100;           // linear ramp from lr / warmup_steps
  double final_lr_fraction = 0.05;  // the cosine ends at learning_rate * this
  uint64_t seed = 1;                // weights, data order and augmentation
  bool resume = false;              // continue from out_dir/checkpoint.pt
  // Train a new model over one already in out_dir (its files are removed first). Without it (or
  // resume), a folder that holds a trained model is refused.
  bool force = false;
  std::string command_line;  // for out_dir/run.json (empty from a library call)
  int threads = 0;           // LibTorch threads (0 = all cores)
  int max_frames = 0;        // use only the first N frames of the split (0 = all)
  // Stop after this many epochs in this call (0 = run to `epochs`); --resume continues. The
  // schedule always spans `epochs`, so a run split this way ends exactly where an uninterrupted one
  // does.
  int max_epochs_this_run = 0;
  int loader_capacity = 3;     // batches prepared ahead
  std::string device = "cpu";  // cpu | cuda (device.h); bit-identical resume needs the same one
  // Data-parallel training over several processes (distributed.h); one process by default.
  DistributedOptions distributed;
  SsdDataOptions data;
  // A new RGB-H training that matches (no data.stereo_dir) uses DefaultRgbhMatchScale() as
  // data.stereo.disparity.match_scale, whatever that holds; model.json records it. `train ssd`
  // sets this unless --match-scale is given; off, data.stereo is used as it is. Not on --resume
  // (model.json's settings win).
  bool auto_match_scale = false;
  SsdTrainerOptions trainer;
  ProgressOptions progress;
  void Check() const;  // throws std::invalid_argument
};

struct TrainSsdSummary : TrainingRunSummary {
  double stereo_seconds = 0;  // the one-off stereo/label pass
  int64_t compression_parameters = 0;
};

// The match scale of a new RGB-H training with auto_match_scale, from the network's input size and
// the first training frame's image size: 0.5 when the network input is about half the image in
// both directions (each ratio in [0.45, 0.55]; KITTI's 1224..1242 x 370..376 px images against the
// default 621 x 188 input), else 1. At 0.5 the stereo match size is about the network's, so the
// height codes need no full-resolution pass and the matcher costs about 1/8 of full resolution
// (docs/BENCHMARKS.md, issue 19).
double DefaultRgbhMatchScale(const SsdConfig& config, int image_width, int image_height);

// Learning rate at `step` of `total_steps` (0-based): warm-up, then cosine to the final fraction.
double ScheduledLearningRate(const TrainSsdOptions& options, int64_t step, int64_t total_steps);

// Trains and writes out_dir/{model.json, model.pt, checkpoint.pt, train_log.csv, run.json}. With
// resume, the model settings come from out_dir/model.json (a mismatching --input is an error) and
// training continues after the checkpoint's epoch; if that is already `epochs`, nothing is
// trained. Before any work it throws: std::invalid_argument when out_dir overlaps the data
// (ROOT/training, ROOT/ImageSets), or when out_dir holds a trained model (model.pt or
// checkpoint.pt) and neither resume (with a checkpoint to resume) nor force is set;
// std::runtime_error naming out_dir in one line when it cannot be written, or when another run
// holds its OutputLock (two trainings into one folder).
TrainSsdSummary TrainSsd(const TrainSsdOptions& options);

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_SSD_TRAIN_H_
