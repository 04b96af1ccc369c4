// Tests of the network through the public, torch-free API (tiny inputs, a few steps: fast).
#include "stereodet/models/ssd/ssd_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "stereodet/models/det3d/det3d_model.h"
#include "stereodet/models/models_test_util.h"
#include "stereodet/models/rpn/rpn_model.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/fuzz_corpus.h"
#include "stereodet/util/hash.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

std::vector<PlanarImage> RandomInputs(const SsdConfig& config, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.0f, 1.0f);
  std::vector<PlanarImage> inputs;
  for (int i = 0; i < n; ++i) {
    PlanarImage p{
        NetworkInputChannels(config.encoding), config.InputHeight(), config.InputWidth(), {}};
    p.data.resize(static_cast<size_t>(p.channels) * p.rows * p.cols);
    for (float& v : p.data) v = value(rng);
    inputs.push_back(std::move(p));
  }
  return inputs;
}

// A batch of frames each with one bright box (class 1) on a dark noisy background.
TrainBatch ToyBatch(const SsdModel& model, int n, unsigned seed) {
  const SsdConfig& config = model.config();
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, 34), y(0, 20), w(12, 28), h(12, 26);
  std::vector<PlanarImage> inputs;
  TrainBatch batch;
  batch.batch_size = n;
  batch.channels = NetworkInputChannels(config.encoding);
  batch.height = config.InputHeight();
  batch.width = config.InputWidth();
  for (int i = 0; i < n; ++i) {
    PlanarImage image{batch.channels, batch.height, batch.width, {}};
    image.data.assign(static_cast<size_t>(batch.channels) * batch.height * batch.width, 0.1f);
    const int left = x(rng), top = y(rng), right = left + w(rng), bottom = top + h(rng);
    for (int c = 0; c < batch.channels; ++c) {
      for (int v = top; v < bottom; ++v) {
        for (int u = left; u < right; ++u) image.Channel(c)[v * batch.width + u] = 0.9f;
      }
    }
    inputs.push_back(std::move(image));
    const MatchResult match = MatchDefaultBoxes(
        model.default_boxes(),
        {{Box2D{double(left), double(top), double(right), double(bottom)}, 1}}, {});
    batch.labels.insert(batch.labels.end(), match.labels.begin(), match.labels.end());
    batch.deltas.insert(batch.deltas.end(), match.deltas.begin(), match.deltas.end());
    batch.num_positive += match.num_positive;
  }
  batch.images = StackPlanar(inputs, batch.channels, batch.height, batch.width);
  return batch;
}

TEST(SsdTest, ParameterCountsEqualApartFromTheLearnedCompression) {
  const SsdModel rgb(SsdConfig{}, 1);
  SsdConfig fixed_config, learned_config;
  fixed_config.encoding = InputEncoding::kRgbhFixed;
  learned_config.encoding = InputEncoding::kRgbhLearned;
  const SsdModel fixed(fixed_config, 1), learned(learned_config, 1);
  EXPECT_EQ(rgb.CompressionParameterCount(), 0);
  EXPECT_EQ(fixed.CompressionParameterCount(), 0);
  EXPECT_EQ(learned.CompressionParameterCount(), 3 * 2);
  EXPECT_EQ(rgb.ParameterCount(), fixed.ParameterCount());
  EXPECT_EQ(learned.ParameterCount() - learned.CompressionParameterCount(), rgb.ParameterCount());
  EXPECT_GT(rgb.ParameterCount(), 100000);
  // The learned compression, folded into the stem, adds one input channel to it: 16 outputs x 9
  // taps per stem output pixel (311 x 94).
  EXPECT_EQ(learned.MultiplyAccumulates() - rgb.MultiplyAccumulates(), 311 * 94 * 16 * 9);
}

TEST(SsdTest, OutputsCoverEveryDefaultBoxAndAreProbabilities) {
  for (InputEncoding encoding :
       {InputEncoding::kRgb, InputEncoding::kRgbhFixed, InputEncoding::kRgbhLearned}) {
    const SsdModel model(TinySsdConfig(encoding), 5);
    const SsdOutputs out = model.Forward(RandomInputs(model.config(), 2, 1));
    EXPECT_EQ(out.num_images, 2);
    EXPECT_EQ(out.num_boxes, static_cast<int>(model.default_boxes().size()));
    EXPECT_EQ(out.num_classes, 4);
    ASSERT_EQ(out.deltas.size(), static_cast<size_t>(2 * out.num_boxes * 4));
    ASSERT_EQ(out.probabilities.size(), static_cast<size_t>(2 * out.num_boxes * 4));
    for (int b = 0; b < 2 * out.num_boxes; b += 97) {
      double sum = 0;
      for (int c = 0; c < 4; ++c) sum += out.probabilities[b * 4 + c];
      EXPECT_NEAR(sum, 1.0, 1e-5);
    }
  }
}

TEST(SsdTest, WrongInputShapeThrows) {
  const SsdModel model(TinySsdConfig(InputEncoding::kRgbhLearned), 5);
  EXPECT_THROW(model.Forward(RandomInputs(TinySsdConfig(InputEncoding::kRgb), 1, 1)),
               std::invalid_argument);
}

TEST(SsdTest, SameSeedSameWeights) {
  const SsdModel a(TinySsdConfig(InputEncoding::kRgb), 9), b(TinySsdConfig(InputEncoding::kRgb), 9),
      c(TinySsdConfig(InputEncoding::kRgb), 10);
  const auto inputs = RandomInputs(a.config(), 1, 2);
  EXPECT_EQ(a.Forward(inputs).deltas, b.Forward(inputs).deltas);
  EXPECT_NE(a.Forward(inputs).deltas, c.Forward(inputs).deltas);
}

TEST(SsdTest, SaveThenLoadGivesIdenticalOutputs) {
  const std::filesystem::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "save_load";
  std::filesystem::remove_all(dir);
  SsdModel model(TinySsdConfig(InputEncoding::kRgbhLearned), 3);
  // Train one step so batch-norm statistics differ from their initial values.
  SsdTrainer trainer(model);
  trainer.Step(ToyBatch(model, 2, 1), 1e-2);
  model.Save(dir);
  const SsdModel loaded = SsdModel::Load(dir);
  EXPECT_EQ(loaded.config().encoding, InputEncoding::kRgbhLearned);
  EXPECT_EQ(loaded.config().InputWidth(), 64);
  const auto inputs = RandomInputs(model.config(), 2, 4);
  const SsdOutputs a = model.Forward(inputs), b = loaded.Forward(inputs);
  EXPECT_EQ(a.deltas, b.deltas);
  EXPECT_EQ(a.probabilities, b.probabilities);
  // No temporaries left behind.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 2);
}

TEST(SsdTest, TheSameWeightsSaveToTheSameBytesAndFingerprint) {
  // model.json's fnv1a64 fingerprints the weights: two trainings that end with the same weights
  // (the experiment on Dask workers and in one process) must write the same model.pt and record
  // the same hash, whatever temporary file names the writers used.
  namespace fs = std::filesystem;
  const fs::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "same_bytes";
  fs::remove_all(dir);
  const SsdModel model(TinySsdConfig(InputEncoding::kRgb), 4);
  model.Save(dir / "a");
  model.Save(dir / "b");
  const std::string a = ReadFile(dir / "a/model.pt"), b = ReadFile(dir / "b/model.pt");
  // Not EXPECT_EQ: a failure would print both archives.
  EXPECT_TRUE(a == b) << "model.pt differs between two saves (" << a.size() << " and " << b.size()
                      << " bytes)";
  const WeightsRecord record = ReadWeightsRecord(ReadFile(dir / "a/model.json"), "a/model.json");
  EXPECT_EQ(record.fnv1a64, ReadWeightsRecord(ReadFile(dir / "b/model.json"), "b").fnv1a64);
  EXPECT_EQ(record.fnv1a64, HashHex(Fnv1a64(a)));
  EXPECT_TRUE(a.find(".model.tmp") == std::string::npos) << "a temporary file's name in model.pt";
}

TEST(SsdTest, LoadRefusesWeightsThatModelJsonDoesNotRecord) {
  namespace fs = std::filesystem;
  const fs::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "tied";
  fs::remove_all(dir);
  // Same encoding and shapes, other weights: LibTorch alone would load them silently.
  SsdModel(TinySsdConfig(InputEncoding::kRgb), 1).Save(dir / "a");
  SsdModel(TinySsdConfig(InputEncoding::kRgb), 2).Save(dir / "b");
  const std::string json = ReadFile(dir / "a/model.json");
  const WeightsRecord record = ReadWeightsRecord(json, "model.json");
  EXPECT_EQ(record.fnv1a64.size(), 16u);
  EXPECT_EQ(record.input_channels, 3);
  EXPECT_EQ(record.parameters, SsdModel::Load(dir / "a").ParameterCount());
  EXPECT_EQ(SsdConfigFromJson(json, "model.json").encoding, InputEncoding::kRgb);
  fs::copy_file(dir / "b/model.pt", dir / "a/model.pt", fs::copy_options::overwrite_existing);
  try {
    SsdModel::Load(dir / "a");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("a/model.pt does not belong to"), std::string::npos) << what;
    EXPECT_NE(what.find("a/model.json"), std::string::npos) << what;
  }
  // A model.json written before the record existed loads unchecked.
  WriteFileAtomically(dir / "a/model.json", SsdConfigToJson(TinySsdConfig(InputEncoding::kRgb)));
  EXPECT_TRUE(ReadWeightsRecord(ReadFile(dir / "a/model.json"), "m").fnv1a64.empty());
  EXPECT_NO_THROW(SsdModel::Load(dir / "a"));
}

TEST(SsdTest, ModelJsonRecordsTheStereoSettingsOfRgbhModels) {
  namespace fs = std::filesystem;
  const fs::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "stereo_record";
  fs::remove_all(dir);
  StereoOptions stereo;
  stereo.disparity.uniqueness_ratio = 5;
  stereo.disparity.num_disparities = 32;
  stereo.ground.enabled = false;
  SsdModel rgbh(TinySsdConfig(InputEncoding::kRgbhFixed), 1);
  EXPECT_TRUE(DifferingStereoSettings(rgbh.stereo(), StereoOptions()).empty());  // new: defaults
  rgbh.set_stereo(stereo);
  rgbh.Save(dir / "rgbh");
  const std::string json = ReadFile(dir / "rgbh/model.json");
  EXPECT_NE(json.find("\"stereo\": {"), std::string::npos) << json;
  const SsdModel back = SsdModel::Load(dir / "rgbh");
  EXPECT_EQ(DifferingStereoSettings(back.stereo(), stereo), "");
  EXPECT_EQ(back.stereo().disparity.uniqueness_ratio, 5);
  EXPECT_EQ(back.stereo().disparity.num_disparities, 32);
  EXPECT_FALSE(back.stereo().ground.enabled);
  // The record is StereoSettingsJson's object; the comparison names each setting.
  EXPECT_NE(DifferingStereoSettings(back.stereo(), StereoOptions())
                .find("disparity.uniqueness_ratio: 5 (requested: 15)"),
            std::string::npos);
  // An rgb model records none; a model.json written before the record existed reads as defaults.
  SsdModel(TinySsdConfig(InputEncoding::kRgb), 1).Save(dir / "rgb");
  EXPECT_EQ(ReadFile(dir / "rgb/model.json").find("\"stereo\""), std::string::npos);
  WriteFileAtomically(dir / "rgbh/model.json",
                      SsdConfigToJson(TinySsdConfig(InputEncoding::kRgbhFixed),
                                      ReadWeightsRecord(json, "model.json")));
  EXPECT_EQ(DifferingStereoSettings(SsdModel::Load(dir / "rgbh").stereo(), StereoOptions()), "");
  EXPECT_EQ(DifferingStereoSettings(ReadStereoRecord("{}", "m"), StereoOptions()), "");
  EXPECT_THROW(ReadStereoRecord("{\"stereo\": 3}", "m"), ParseError);
  EXPECT_THROW(
      ReadStereoRecord("{\"stereo\": {\"disparity\": {\"uniqueness_ratio\": \"x\"}}}", "m"),
      ParseError);
}

TEST(SsdTest, LoadReportsMissingFiles) {
  EXPECT_THROW(SsdModel::Load("/nonexistent/model"), std::runtime_error);
}

TEST(SsdTest, AFewStepsLowerTheLoss) {
  SetTorchThreads(1);
  SsdModel model(TinySsdConfig(InputEncoding::kRgb), 21);
  SsdTrainer trainer(model);
  const TrainBatch batch = ToyBatch(model, 4, 2);
  ASSERT_GT(batch.num_positive, 0);
  const double first = trainer.Step(batch, 1e-2).total;
  double last = first;
  for (int i = 0; i < 15; ++i) last = trainer.Step(batch, 1e-2).total;
  EXPECT_TRUE(std::isfinite(first));
  EXPECT_LT(last, 0.5 * first);
}

// A diverged training's weights (NaN or inf, with a model.json that records their hash) would give
// empty or arbitrary detections with exit 0; opening the model refuses them, naming the tensor.
TEST(SsdTest, LoadRefusesNonFiniteWeightsOfADivergedTraining) {
  SetTorchThreads(1);
  const std::filesystem::path dir = ::stereodet::TestBinaryDir() / "models_test_tmp" / "diverged";
  std::filesystem::remove_all(dir);
  SsdModel model(TinySsdConfig(InputEncoding::kRgb), 5);
  SsdTrainer trainer(model);
  const TrainBatch batch = ToyBatch(model, 2, 4);
  for (int i = 0; i < 5; ++i) trainer.Step(batch, 1e30);  // diverges: inf, then NaN
  model.Save(dir);
  EXPECT_THAT([&] { SsdModel::Load(dir); }, ::testing::ThrowsMessage<std::runtime_error>(HasSubstr(
                                                "holds non-finite weights (NaN or inf) in '")));
  std::filesystem::remove_all(dir);
}

TEST(SsdTest, ResumingFromACheckpointContinuesExactly) {
  SetTorchThreads(1);
  const std::filesystem::path path =
      ::stereodet::TestBinaryDir() / "models_test_tmp" / "resume" / "checkpoint.pt";
  std::filesystem::remove_all(path.parent_path());
  SsdModel model(TinySsdConfig(InputEncoding::kRgbhLearned), 4);
  SsdTrainer trainer(model);
  const TrainBatch batch = ToyBatch(model, 2, 3);
  trainer.Step(batch, 1e-2);
  trainer.Step(batch, 1e-2);
  trainer.SaveCheckpoint(path, 7);
  const double continued = trainer.Step(batch, 1e-2).total;
  const double next = trainer.Step(batch, 1e-2).total;

  SsdModel fresh(TinySsdConfig(InputEncoding::kRgbhLearned), 99);
  SsdTrainer resumed(fresh);
  EXPECT_EQ(resumed.LoadCheckpoint(path), 7);
  EXPECT_DOUBLE_EQ(resumed.Step(batch, 1e-2).total, continued);
  // The optimizer's moments were restored too, so the step after matches as well.
  EXPECT_DOUBLE_EQ(resumed.Step(batch, 1e-2).total, next);
}

TEST(SsdTest, ACheckpointOfAnotherRunOrModelIsRefusedNamingWhy) {
  SetTorchThreads(1);
  const std::filesystem::path path =
      ::stereodet::TestBinaryDir() / "models_test_tmp" / "tied" / "checkpoint.pt";
  std::filesystem::remove_all(path.parent_path());
  SsdModel model(TinySsdConfig(InputEncoding::kRgb), 4);
  SsdTrainer(model).SaveCheckpoint(path, 3, "00000000000000aa");

  SsdModel same(TinySsdConfig(InputEncoding::kRgb), 5);
  SsdTrainer same_trainer(same);
  EXPECT_EQ(same_trainer.LoadCheckpoint(path, "00000000000000aa"), 3);
  EXPECT_EQ(same_trainer.LoadCheckpoint(path), 3);  // no run to check against: config only
  try {
    same_trainer.LoadCheckpoint(path, "00000000000000bb");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(),
                HasSubstr(path.string() + " is from another training run "
                                          "(00000000000000aa) than the folder's model.json "
                                          "(00000000000000bb)"));
  }
  // Another input encoding: the first setting that differs is named, before LibTorch's shapes.
  SsdModel other(TinySsdConfig(InputEncoding::kRgbhFixed), 5);
  SsdTrainer other_trainer(other);
  try {
    other_trainer.LoadCheckpoint(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr(path.string() + " was written for another model: encoding: "
                                                    "\"rgb\" here, \"rgbh-fixed\" in the model"));
  }
  SsdConfig wider = TinySsdConfig(InputEncoding::kRgb);
  wider.base_channels *= 2;
  SsdModel wide(wider, 5);
  SsdTrainer wide_trainer(wide);
  EXPECT_THROW(
      {
        try {
          wide_trainer.LoadCheckpoint(path);
        } catch (const std::runtime_error& e) {
          EXPECT_THAT(e.what(), HasSubstr("base_channels: "));
          throw;
        }
      },
      std::runtime_error);
}

}  // namespace
}  // namespace stereodet
