#include "stereodet/models/rpn/rpn_train.h"

#include <fmt/format.h>

#include <cmath>

#include "stereodet/models/train_common.h"
#include "stereodet/models/train_data.h"
#include "stereodet/models/trainer.h"
#include "stereodet/util/check.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

// The seed of a step's anchor and RoI sampling (and of torch's generator): a function of the run's
// seed and the global step only, so a resumed run draws what an uninterrupted one draws.
uint64_t StepSeed(uint64_t seed, int64_t step) {
  return SampleSeed(seed ^ 0x52504e5f53544550ULL, static_cast<int>(step), -3);
}

// The two-stage detector's part of the training loop: a batch's samples drawn in parallel, each
// from its own seed, then one step of the RPN and head losses.
class RpnTrainingTask : public ModelTrainingTask<RpnModel, RpnTrainer, TrainRpnOptions> {
 public:
  RpnTrainingTask(const TrainingRun<TrainRpnOptions>& run, const RpnModel& model,
                  RpnTrainer& trainer, const RpnTrainingData& data)
      : ModelTrainingTask(run, model, trainer), data_(data) {}

  StepLoss Step(int epoch, int64_t step, const std::vector<int>& batch_frames,
                double learning_rate) override {
    std::vector<RpnSample> samples =
        MakeBatchSamples(batch_frames, options_.seed, epoch, options_.threads,
                         [&](int index, uint64_t seed) { return data_.Sample(index, seed); });
    const uint64_t step_seed = StepSeed(options_.seed, step);
    RpnBatch batch;
    for (size_t k = 0; k < samples.size(); ++k) {
      batch.inputs.push_back(std::move(samples[k].input));
      batch.objects.push_back(std::move(samples[k].objects));
      batch.sampling_seeds.push_back(SampleSeed(step_seed, 0, batch_frames[k]));
    }
    const RpnLossParts loss = trainer_.Step(batch, learning_rate, step_seed);
    return {loss.total,
            {loss.objectness, loss.rpn_box, loss.head_class, loss.head_box},
            {loss.positive_anchors, loss.foreground_rois}};
  }

 private:
  const RpnTrainingData& data_;
};

}  // namespace

void TrainRpnOptions::Check() const {
  model.Check();
  data.Check();
  trainer.Check();
  CheckTrainingSchedule(*this);
  STEREODET_CHECK(!init_geometry || !init_from.empty()) << "--init-geometry needs --init-from";
}

TrainRpnSummary TrainRpn(const TrainRpnOptions& given) {
  TrainingRun<TrainRpnOptions> run(given, "train rpn", {{"--init-from", given.init_from}});
  const TrainRpnOptions& options = run.options();
  TrainRpnSummary summary;
  const bool resuming = run.folder().resuming();
  const RpnConfig config = run.folder().ModelConfig(
      options.model, RpnConfigFromJson,
      [](const RpnConfig& c) { return std::string(RpnInputName(c.input)); });
  RpnDataOptions data_options = options.data;
  if (resuming && config.input == RpnInput::kRgbd) {
    // The geometry the model was trained on so far, whatever the flags say now.
    data_options.stereo =
        ReadRpnStereoRecord(run.folder().config_text(), run.folder().config_path().string());
  }

  const KittiDataset dataset(options.data_root, "training");
  const std::vector<std::string> ids = TrainingFrameIds(dataset, options.split, options.max_frames);

  RpnModel model(config, options.seed, run.device());
  model.set_stereo(data_options.stereo);
  // In a training group, rank 0's initialization reaches the others (Resume's SetGroup).
  if (!resuming && !options.init_from.empty() &&
      (run.group() == nullptr || run.group()->IsRoot())) {
    const RpnModel rgb = RpnModel::Load(options.init_from, run.device());
    summary.init_tensors = model.InitFrom(rgb, options.init_geometry);
  }
  RpnTrainer trainer(model, options.trainer);
  summary.parameters = model.ParameterCount();
  summary.image_branch_parameters = model.ImageBranchParameterCount();
  summary.geometry_branch_parameters = model.GeometryBranchParameterCount();
  if (!run.Resume(trainer, summary)) return summary;

  const Timer stereo_timer;
  const RpnTrainingData data(dataset, ids, config, data_options, options.progress);
  summary.stereo_seconds = stereo_timer.ElapsedSeconds();
  summary.frames = data.size();
  summary.objects = data.NumObjects();

  TrainingLoopOptions loop = run.LoopOptions(data.size());
  loop.columns = {.frames = "frames",
                  .terms = {"objectness_loss", "rpn_box_loss", "head_class_loss", "head_box_loss"},
                  .term_labels = {"obj", "rpn-box", "cls", "box"},
                  .counts = {"positive_anchors", "foreground_rois"},
                  .rate = "images_per_s"};
  if (!options.init_from.empty()) {
    loop.manifest.inputs.push_back({"init_from", options.init_from.string()});
  }
  loop.settings_json = [&](int epochs_done) {
    return fmt::format(
        R"({{"input": "{}", {}, "input_width": {}, "input_height": {}, )"
        R"("image_width": {}, "geometry_width": {}, "threads": {}, "device": "{}", )"
        R"("augment": {}, "init_from": "{}", "init_geometry": {}, "parameters": {}}})",
        RpnInputName(config.input), run.ScheduleSettings(epochs_done, ids.size()),
        config.input_width, config.input_height, config.image_width, config.geometry_width,
        options.threads, options.device, options.data.augment, options.init_from.string(),
        options.init_geometry, summary.parameters);
  };
  RpnTrainingTask task(run, model, trainer, data);
  run.Train(task, loop, summary);
  return summary;
}

}  // namespace stereodet
