#include "stereodet/models/det3d/det3d_train.h"

#include <fmt/format.h>

#include <cmath>

#include "stereodet/models/det3d/gt_database.h"
#include "stereodet/models/train_common.h"
#include "stereodet/models/train_data.h"
#include "stereodet/models/trainer.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"

namespace stereodet {

namespace {

// The 3D detector's part of the training loop: a batch's frames augmented in parallel (GT
// sampling, then AugmentFrame), each from its own seed, then one step of its losses.
class Det3dTrainingTask : public ModelTrainingTask<Det3dModel, Det3dTrainer, TrainDet3dOptions> {
 public:
  Det3dTrainingTask(const TrainingRun<TrainDet3dOptions>& run, const Det3dModel& model,
                    Det3dTrainer& trainer, const std::vector<Det3dFrame>& frames,
                    const GtDatabase& gt_database, bool gt_sampling)
      : ModelTrainingTask(run, model, trainer),
        frames_(frames),
        gt_database_(gt_database),
        gt_sampling_(gt_sampling) {}

  StepLoss Step(int epoch, int64_t /*step*/, const std::vector<int>& batch_frames,
                double learning_rate) override {
    const std::vector<Det3dSample> batch = MakeBatchSamples(
        batch_frames, options_.seed, epoch, options_.threads, [&](int index, uint64_t seed) {
          // GT sampling draws from ~seed: a stream apart from AugmentFrame's, both fixed by
          // (seed, epoch, frame), so a resumed training samples the same objects.
          const Det3dFrame augmented =
              gt_sampling_ ? AugmentFrame(SampleGtObjects(frames_[index], gt_database_,
                                                          options_.gt_sampling, ~seed)
                                              .frame,
                                          options_.augment, seed)
                           : AugmentFrame(frames_[index], options_.augment, seed);
          return MakeDet3dSample(augmented, model_.config(), model_.anchors(), true,
                                 options_.max_aux_points);
        });
    const Det3dLossParts loss = trainer_.Step(batch, learning_rate);
    return {loss.total,
            {loss.classification, loss.box, loss.direction, loss.part_warp, loss.segmentation,
             loss.centre},
            {}};
  }

 private:
  const std::vector<Det3dFrame>& frames_;
  const GtDatabase& gt_database_;
  const bool gt_sampling_;
};

}  // namespace

void TrainDet3dOptions::Check() const {
  model.Check();
  filter.Check();
  augment.Check();
  gt_database.Check();
  gt_sampling.Check();
  loss.Check();
  CheckTrainingSchedule(*this);
  STEREODET_CHECK(model.input != PointSource::kStereo || !points_dir.empty())
      << "--input stereo needs --points (the folder `stereodet stereo --encode points` wrote)";
  STEREODET_CHECK(weight_decay >= 0.0 && std::isfinite(weight_decay))
      << "weight decay must be >= 0, got " << weight_decay;
  STEREODET_CHECK(max_aux_points >= 0) << "max_aux_points must be >= 0, got " << max_aux_points;
}

TrainDet3dSummary TrainDet3d(const TrainDet3dOptions& given) {
  TrainingRun<TrainDet3dOptions> run(given, "train det3d", {{"--points", given.points_dir}});
  const TrainDet3dOptions& options = run.options();
  TrainDet3dSummary summary;
  const Det3dConfig config = run.folder().ModelConfig(
      options.model, Det3dConfigFromJson,
      [](const Det3dConfig& c) { return std::string(PointSourceName(c.input)); });

  const KittiDataset dataset(options.data_root, "training");
  const std::vector<std::string> ids = TrainingFrameIds(dataset, options.split, options.max_frames);

  Det3dModel model(config, options.seed, run.device());
  Det3dTrainer trainer(model, options.loss, options.weight_decay);
  summary.parameters = model.ParameterCount();
  summary.auxiliary_parameters = model.AuxiliaryParameterCount();
  if (!run.Resume(trainer, summary)) return summary;

  // Every frame in memory once (points and boxes); augmentation works on copies.
  std::vector<Det3dFrame> frames(ids.size());
  {
    ProgressReporter progress("load", static_cast<int64_t>(ids.size()), options.progress);
    ParallelFor(
        ids.size(),
        [&](size_t i) {
          frames[i] = LoadDet3dFrame(dataset, options.points_dir, config.input, ids[i],
                                     config.classes, config.grid, options.filter,
                                     /*with_labels=*/true);
        },
        options.threads);
    progress.Add(static_cast<int64_t>(ids.size()));
  }
  summary.frames = static_cast<int>(frames.size());
  for (const Det3dFrame& f : frames) summary.objects += static_cast<int>(f.boxes.size());
  // GT-database sampling: the objects of these very frames, so of the model's input only.
  const bool gt_sampling = options.augment.enabled && options.gt_sampling.enabled;
  GtDatabase gt_database;
  if (gt_sampling) {
    gt_database = BuildGtDatabase(frames, static_cast<int>(config.classes.size()), config.input,
                                  options.gt_database);
  }
  summary.gt_database_objects = gt_database.ObjectCount();
  summary.gt_database_points = gt_database.PointCount();

  TrainingLoopOptions loop = run.LoopOptions(static_cast<int>(frames.size()));
  // The progress line leaves the direction term out (it is small and steady).
  loop.columns = {.frames = "frames",
                  .terms = {"classification_loss", "box_loss", "direction_loss", "part_warp_loss",
                            "segmentation_loss", "centre_loss"},
                  .term_labels = {"cls", "box", "", "psw", "seg", "ctr"},
                  .counts = {},
                  .rate = "frames_per_s"};
  if (!options.points_dir.empty()) {
    loop.manifest.inputs.push_back({"points", options.points_dir.string()});
  }
  loop.settings_json = [&](int epochs_done) {
    return fmt::format(
        R"({{"input": "{}", {}, "base_channels": {}, "pillar_m": {}, "device": "{}", )"
        R"("augment": {}, "auxiliary": {}, "stereo_max_distance_m": {}, "camera_fov_only": {}, )"
        R"("crop_to_grid": {}, "gt_sampling": {}, "gt_per_class": {}, "gt_min_points": {}, )"
        R"("gt_box_margin_m": {}, "gt_database_objects": {}}})",
        PointSourceName(config.input), run.ScheduleSettings(epochs_done, ids.size()),
        config.base_channels, config.grid.pillar_m, options.device, options.augment.enabled,
        options.loss.auxiliary, options.filter.stereo_max_distance_m,
        options.filter.camera_fov_only, options.filter.crop_to_grid, gt_sampling,
        options.gt_sampling.max_per_class, options.gt_database.min_points,
        options.gt_database.box_margin_m, gt_database.ObjectCount());
  };
  Det3dTrainingTask task(run, model, trainer, frames, gt_database, gt_sampling);
  run.Train(task, loop, summary);
  return summary;
}

}  // namespace stereodet
