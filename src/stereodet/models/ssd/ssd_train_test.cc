// End to end on a tiny KITTI-format dataset written by the test: train, resume, detect (seconds).
#include "stereodet/models/ssd/ssd_train.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "stereodet/geometry/calibration.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/detect_shard.h"
#include "stereodet/models/models_test_util.h"
#include "stereodet/models/ssd/ssd_detect.h"
#include "stereodet/models/ssd/ssd_model.h"
#include "stereodet/models/train_common.h"
#include "stereodet/stereo/dataset_encoder.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/run_manifest.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// Frames of 256 x 80 px, one car per frame, 20 px further right in each (WriteTinyImageDataset).
fs::path WriteTinyDataset(const std::string& name, int frames) {
  return WriteTinyImageDataset(name, frames, {256, 80}, 90, 160,
                               [](int i) { return cv::Rect(40 + 20 * i, 30, 70, 36); });
}

StereoOptions TinyStereo() {
  StereoOptions stereo;
  stereo.disparity.num_disparities = 32;
  stereo.ground.enabled = false;
  return stereo;
}

TrainSsdOptions TinyTraining(const fs::path& root, const fs::path& out) {
  TrainSsdOptions options = TinyTrainingOptions<TrainSsdOptions>(root, out);
  options.model.encoding = InputEncoding::kRgbhLearned;
  options.model.boxes.input_width = 128;
  options.model.boxes.input_height = 40;
  options.model.base_channels = 4;
  options.batch_size = 2;
  options.warmup_steps = 2;
  options.data.threads = 1;
  options.data.stereo = TinyStereo();
  return options;
}

int CountLines(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) ++n;
  return n;
}

TEST(SsdTrainTest, ScheduleWarmsUpThenDecays) {
  TrainSsdOptions options;
  options.learning_rate = 1.0;
  options.warmup_steps = 10;
  options.final_lr_fraction = 0.1;
  EXPECT_DOUBLE_EQ(ScheduledLearningRate(options, 0, 100), 0.1 * (0.1 + 0.9 * 1.0));
  EXPECT_NEAR(ScheduledLearningRate(options, 99, 100), 0.1, 1e-12);
  EXPECT_GT(ScheduledLearningRate(options, 10, 100), ScheduledLearningRate(options, 50, 100));
}

// A new RGB-H training with auto_match_scale (`train ssd` without --match-scale) matches at 0.5
// when the network sees about half the image, model.json records it, and `detect ssd` uses it;
// models recorded without the key (the committed ones) read as 1.
TEST(SsdTrainTest, NewRgbhTrainingsMatchAtTheNetworksScale) {
  const SsdConfig config;  // 621 x 188
  EXPECT_EQ(DefaultRgbhMatchScale(config, 1242, 375), 0.5);
  EXPECT_EQ(DefaultRgbhMatchScale(config, 1224, 370), 0.5);
  EXPECT_EQ(DefaultRgbhMatchScale(config, 621, 188), 1.0);   // the network sees it whole
  EXPECT_EQ(DefaultRgbhMatchScale(config, 1242, 188), 1.0);  // half across only
  EXPECT_EQ(DefaultRgbhMatchScale(config, 2484, 750), 1.0);  // a quarter
  EXPECT_THROW(DefaultRgbhMatchScale(config, 0, 375), std::invalid_argument);

  const fs::path root = WriteTinyDataset("scale_data", 2);
  TrainSsdOptions options =
      TinyTraining(root, ModelsTestDir("scale_model"));  // 256 x 80 -> 128 x 40
  options.epochs = 1;
  options.auto_match_scale = true;
  TrainSsd(options);
  const std::optional<StereoOptions> recorded = ModelStereoSettings(options.out_dir);
  ASSERT_TRUE(recorded.has_value());
  EXPECT_EQ(recorded->disparity.match_scale, 0.5);
  EXPECT_EQ(recorded->disparity.num_disparities, 32);  // the full-resolution setting is recorded
  DetectSsdOptions detect =
      TinyDetectOptions<DetectSsdOptions>(options.out_dir, root, ModelsTestDir("scale_det"));
  EXPECT_EQ(DetectSsd(detect).frames, 2);
  EXPECT_NE(ReadFile(detect.out_dir / "run.json").find("\"match_scale\": 0.5"), std::string::npos);
  // Asking for full resolution is a named mismatch.
  detect.stereo = *recorded;
  detect.stereo->disparity.match_scale = 1.0;
  EXPECT_EQ(StereoMismatch(detect), "disparity.match_scale: 0.5 (requested: 1.0)");
  // Without auto_match_scale the settings are used as given.
  TrainSsdOptions as_given = TinyTraining(root, ModelsTestDir("scale_model_given"));
  as_given.epochs = 1;
  TrainSsd(as_given);
  EXPECT_EQ(ModelStereoSettings(as_given.out_dir)->disparity.match_scale, 1.0);
  // The committed RGB-H models (trained with the half-size default) record 0.5; the same
  // model.json without the key (as models trained before the option were written) reads as 1.
  for (const char* model : {"models/ssd-rgbh-fixed", "models/ssd-rgbh-learned"}) {
    const fs::path dir = TestSourceDir() / model;
    if (!fs::exists(dir / "model.json")) continue;
    const std::optional<StereoOptions> committed = ModelStereoSettings(dir);
    ASSERT_TRUE(committed.has_value()) << model;
    EXPECT_EQ(committed->disparity.match_scale, 0.5) << model;
    const std::string json = ReadFile(dir / "model.json");
    const std::string key = "\"match_scale\": 0.5,";
    const size_t at = json.find(key);
    ASSERT_NE(at, std::string::npos) << model;
    const fs::path old_dir = ModelsTestDir("scale_old_model");
    std::ofstream(old_dir / "model.json") << json.substr(0, at) << json.substr(at + key.size());
    const std::optional<StereoOptions> old = ModelStereoSettings(old_dir);
    ASSERT_TRUE(old.has_value()) << model;
    EXPECT_EQ(old->disparity.match_scale, 1.0) << model;
  }
}

TEST(SsdTrainTest, TrainResumeAndDetectEndToEnd) {
  const fs::path root = WriteTinyDataset("e2e_data", 4);
  const fs::path out = ModelsTestDir("e2e_model");

  // Three epochs, interrupted after two, then resumed.
  TrainSsdOptions options = TinyTraining(root, out);
  options.epochs = 3;
  options.max_epochs_this_run = 2;
  TrainSsdSummary s = TrainSsd(options);
  EXPECT_EQ(s.frames, 4);
  EXPECT_EQ(s.epochs_done, 2);
  EXPECT_EQ(s.compression_parameters, 6);
  for (const char* file : {"model.json", "model.pt", "checkpoint.pt", "train_log.csv"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  EXPECT_EQ(CountLines(out / "train_log.csv"), 3);
  options.max_epochs_this_run = 0;
  options.resume = true;
  // --resume takes model.json's config: another input or input size is refused, naming both.
  auto refusal = [](const TrainSsdOptions& o) -> std::string {
    try {
      TrainSsd(o);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  TrainSsdOptions other = options;
  other.model.encoding = InputEncoding::kRgb;
  EXPECT_NE(refusal(other).find("was trained with --input rgbh-learned, not rgb"),
            std::string::npos)
      << refusal(other);
  other = options;
  other.model.boxes.input_width = 64;
  EXPECT_NE(refusal(other).find("has input size 128x40, not 64x40"), std::string::npos)
      << refusal(other);
  s = TrainSsd(options);
  EXPECT_EQ(s.epochs_run, 1);
  EXPECT_EQ(s.epochs_done, 3);
  EXPECT_EQ(CountLines(out / "train_log.csv"), 4);

  // An uninterrupted 3-epoch run ends with the same weights.
  const fs::path straight = ModelsTestDir("e2e_straight");
  TrainSsdOptions direct = TinyTraining(root, straight);
  direct.epochs = 3;
  TrainSsd(direct);
  const SsdModel a = SsdModel::Load(out), b = SsdModel::Load(straight);
  PlanarImage input{4, 40, 128, std::vector<float>(4 * 40 * 128, 0.5f)};
  EXPECT_EQ(a.Forward({input}).probabilities, b.Forward({input}).probabilities);

  // A mismatching --input on resume is refused.
  TrainSsdOptions wrong = options;
  wrong.model.encoding = InputEncoding::kRgb;
  EXPECT_THROW(TrainSsd(wrong), std::invalid_argument);

  // Training again into a folder that holds a model is refused unless --resume or --force ...
  const std::string weights = ReadFile(straight / "model.pt");
  try {
    TrainSsd(direct);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("holds a trained model (model.pt); use --resume"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadFile(straight / "model.pt"), weights);  // untouched
  // ... and an --out inside the data is refused before any work.
  TrainSsdOptions inside = TinyTraining(root, root / "training" / "model");
  EXPECT_THROW(TrainSsd(inside), std::invalid_argument);
  EXPECT_FALSE(fs::exists(root / "training" / "model"));
  // run.json records the run.
  const std::string run = ReadFile(out / "run.json");
  EXPECT_NE(run.find("\"tool\": \"train ssd\""), std::string::npos) << run;
  EXPECT_NE(run.find("\"epochs_done\": 3"), std::string::npos) << run;

  // Detection writes one parseable file per frame, also with blur.
  for (double sigma : {0.0, 3.0}) {
    DetectSsdOptions detect = TinyDetectOptions<DetectSsdOptions>(
        out, root, ModelsTestDir(sigma > 0 ? "e2e_det_blur" : "e2e_det"));
    detect.blur_sigma_px = sigma;
    detect.stereo = TinyStereo();
    detect.batch_size = 3;
    // A stale file of an earlier detection run in the folder does not survive the new run.
    RunManifest earlier;
    earlier.tool = "detect ssd";
    WriteRunManifest(detect.out_dir, earlier);
    WriteFileAtomically(detect.out_dir / "000099.txt",
                        "Car -1 -1 -10 0 0 1 1 -1 -1 -1 -1000 -1000 -1000 -10 0.5\n");
    const DetectSummary d = DetectSsd(detect);
    EXPECT_EQ(d.frames, 4);
    EXPECT_FALSE(fs::exists(detect.out_dir / "000099.txt"));
    const std::optional<RunManifest> manifest = ReadRunManifest(detect.out_dir);
    ASSERT_TRUE(manifest.has_value());
    EXPECT_EQ(manifest->tool, "detect ssd");
    ASSERT_EQ(manifest->frames.size(), 4u);
    EXPECT_EQ(manifest->frames[3].first, FrameId(3));
    EXPECT_EQ(manifest->frames[3].second, HashFileHex(detect.out_dir / (FrameId(3) + ".txt")));
    for (int i = 0; i < 4; ++i) {
      const fs::path file = detect.out_dir / (FrameId(i) + ".txt");
      ASSERT_TRUE(fs::exists(file));
      ObjectParseOptions parse;
      parse.kind = ObjectFileKind::kDetection;
      for (const Object& o : ReadObjects(file, parse).objects) {
        EXPECT_FALSE(o.Has3D());
        EXPECT_GE(o.box.left, 0.0);
        EXPECT_LE(o.box.right, 256.0);
        EXPECT_TRUE(o.score.has_value());
      }
    }
    // run.json records the stereo settings the heights were made with.
    EXPECT_NE(ReadFile(detect.out_dir / "run.json").find("\"num_disparities\": 32"),
              std::string::npos);
    // The pipelined frame loop (the default) writes exactly what the sequential one writes, for
    // one and for several frames a batch.
    for (int batch_size : {1, 3}) {
      DetectSsdOptions sequential = detect;
      sequential.pipeline = false;
      sequential.batch_size = batch_size;
      sequential.out_dir = ModelsTestDir("e2e_det_sequential");
      DetectSsdOptions pipelined = sequential;
      pipelined.pipeline = true;
      pipelined.out_dir = ModelsTestDir("e2e_det_pipelined");
      DetectSsd(sequential);
      DetectSsd(pipelined);
      for (int i = 0; i < 4; ++i) {
        const std::string file = FrameId(i) + ".txt";
        const std::string text = ReadFile(pipelined.out_dir / file);
        EXPECT_FALSE(text.empty()) << file;
        EXPECT_TRUE(text == ReadFile(sequential.out_dir / file))
            << file << ", batch " << batch_size;
        // (LibTorch's kernels round differently for another batch size: compare like with like.)
        if (batch_size == detect.batch_size) {
          EXPECT_TRUE(text == ReadFile(detect.out_dir / file)) << file;
        }
      }
    }
  }
}

// --stereo DIR: the heights of a `stereodet stereo` folder made with the model's settings give the
// same detections and the same training as matching; a folder of other settings is refused.
TEST(SsdTrainTest, StereoFolderHeightsGiveWhatMatchingGives) {
  const fs::path root = WriteTinyDataset("stdir_data", 4);
  const KittiDataset dataset(root, "training");
  const std::vector<std::string> ids = dataset.ReadSplit("val");
  auto encode = [&](const std::string& name, const StereoOptions& stereo) {
    const fs::path dir = ModelsTestDir(name);
    fs::remove_all(dir);
    EncodeDatasetOptions encode_options;
    encode_options.stereo = stereo;
    encode_options.num_threads = 1;
    encode_options.progress.stream = nullptr;
    EncodeDataset(dataset, ids, dir, encode_options);
    return dir;
  };
  const fs::path stereo_dir = encode("stdir_stereo", TinyStereo());
  StereoOptions other = TinyStereo();
  other.disparity.num_disparities = 48;
  const fs::path other_dir = encode("stdir_stereo48", other);

  // Training: one epoch from the folder's heights ends with the weights of one from matching.
  TrainSsdOptions matched = TinyTraining(root, ModelsTestDir("stdir_model"));
  matched.epochs = 1;
  TrainSsd(matched);
  TrainSsdOptions read = TinyTraining(root, ModelsTestDir("stdir_model_read"));
  read.epochs = 1;
  read.data.stereo = StereoOptions();  // ignored: the folder's settings are used
  read.data.stereo_dir = stereo_dir;
  TrainSsd(read);
  const SsdModel a = SsdModel::Load(matched.out_dir), b = SsdModel::Load(read.out_dir);
  EXPECT_EQ(b.stereo().disparity.num_disparities, 32);  // model.json records the folder's
  PlanarImage input{4, 40, 128, std::vector<float>(4 * 40 * 128, 0.5f)};
  EXPECT_EQ(a.Forward({input}).probabilities, b.Forward({input}).probabilities);
  // Resuming a model with another folder's settings is refused, naming the setting.
  TrainSsdOptions resume = read;
  resume.epochs = 2;
  resume.resume = true;
  resume.data.stereo_dir = other_dir;
  try {
    TrainSsd(resume);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("disparity.num_disparities: 32 (requested: 48)"),
              std::string::npos)
        << e.what();
  }

  // Detection, sharp and blurred.
  for (double sigma : {0.0, 2.0}) {
    DetectSsdOptions detect;
    detect.model_dir = matched.out_dir;
    detect.data_root = root;
    detect.blur_sigma_px = sigma;
    detect.threads = 1;
    detect.batch_size = 2;
    detect.progress.stream = nullptr;
    detect.out_dir = ModelsTestDir("stdir_det_matched");
    DetectSsd(detect);
    DetectSsdOptions from_folder = detect;
    from_folder.stereo_dir = stereo_dir;
    from_folder.out_dir = ModelsTestDir("stdir_det_read");
    DetectSsd(from_folder);
    for (const std::string& id : ids) {
      const std::string text = ReadFile(from_folder.out_dir / (id + ".txt"));
      EXPECT_FALSE(text.empty()) << id;
      EXPECT_TRUE(text == ReadFile(detect.out_dir / (id + ".txt"))) << id << ", sigma " << sigma;
    }
    EXPECT_NE(ReadFile(from_folder.out_dir / "run.json").find("stdir_stereo"), std::string::npos);
  }
  DetectSsdOptions detect;
  detect.model_dir = matched.out_dir;
  detect.data_root = root;
  detect.progress.stream = nullptr;
  detect.out_dir = ModelsTestDir("stdir_det_refused");
  detect.stereo_dir = other_dir;
  try {
    DetectSsd(detect);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("its stereo.json records other stereo settings than the "
                                         "model's model.json: disparity.num_disparities: 32 "
                                         "(stereo.json: 48)"),
              std::string::npos)
        << e.what();
  }
  detect.stereo_dir = root;  // no stereo.json
  try {
    DetectSsd(detect);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is not a `stereodet stereo` folder"), std::string::npos)
        << e.what();
  }
  // A frame the folder has not finished is named.
  detect.stereo_dir = stereo_dir;
  fs::remove(stereo_dir / "ground" / (ids[1] + ".txt"));
  try {
    DetectSsd(detect);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("has no finished frame " + ids[1]), std::string::npos)
        << e.what();
  }
}

TEST(SsdDetectTest, RefusesAnOutputInsideTheInputsOrAForeignFolder) {
  const fs::path root = WriteTinyDataset("refuse_data", 1);
  DetectSsdOptions detect;
  detect.model_dir = root / "no_model_needed";  // refused before the model is read
  detect.data_root = root;
  detect.progress.stream = nullptr;
  const std::string labels = ReadFile(root / "training/label_2/000000.txt");
  detect.out_dir = root / "training/label_2";
  try {
    DetectSsd(detect);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("label_2 is inside the input --data"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadFile(root / "training/label_2/000000.txt"), labels);
  detect.out_dir = detect.model_dir / "det";
  EXPECT_THROW(DetectSsd(detect), std::invalid_argument);
  // A folder of other files (no run.json of detect) is not an earlier detection folder.
  detect.out_dir = ModelsTestDir("refuse_foreign");
  WriteFileAtomically(detect.out_dir / "notes.txt", "mine");
  try {
    DetectSsd(detect);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(" is a folder of other files (notes.txt); detect ssd "
                                         "replaces or writes into only a folder that detect"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadFile(detect.out_dir / "notes.txt"), "mine");
}

TEST(SsdTrainTest, WarmupWarningOnlyWhenTheWarmupOutlastsTheTraining) {
  EXPECT_EQ(WarmupWarning(100, 6, 2),
            "warning: this training has 12 steps (2 epochs of 6), fewer than the learning-rate "
            "warm-up's 100; it never reaches the peak rate (more --epochs, more frames or a "
            "smaller --batch-size)\n");
  EXPECT_NE(WarmupWarning(13, 6, 2), "");
  EXPECT_NE(WarmupWarning(2, 1, 1).find("(1 epoch of 1)"), std::string::npos);
  EXPECT_EQ(WarmupWarning(12, 6, 2), "");
  EXPECT_EQ(WarmupWarning(0, 1, 1), "");
}

// Reads what a training wrote to its progress stream.
std::string TrainAndCaptureProgress(TrainSsdOptions options) {
  std::FILE* stream = std::tmpfile();
  options.progress.stream = stream;
  options.progress.mode = ProgressOptions::Mode::kPlain;
  TrainSsd(options);
  std::fflush(stream);
  std::rewind(stream);
  std::string text;
  char buffer[4096];
  while (size_t n = std::fread(buffer, 1, sizeof buffer, stream)) text.append(buffer, n);
  std::fclose(stream);
  return text;
}

TEST(SsdTrainTest, TrainingShorterThanTheWarmupWarnsOnce) {
  const fs::path root = WriteTinyDataset("warmup_data", 2);
  TrainSsdOptions options = TinyTraining(root, ModelsTestDir("warmup_model"));
  options.model.encoding = InputEncoding::kRgb;
  options.epochs = 1;  // 1 step of 2 frames
  options.warmup_steps = 5;
  std::string text = TrainAndCaptureProgress(options);
  size_t at = text.find(
      "warning: this training has 1 steps (1 epoch of 1), fewer than the "
      "learning-rate warm-up's 5");
  EXPECT_NE(at, std::string::npos) << text;
  EXPECT_EQ(text.find("warning:", at + 1), std::string::npos) << text;  // once
  options.force = true;
  options.warmup_steps = 1;
  text = TrainAndCaptureProgress(options);
  EXPECT_EQ(text.find("warning:"), std::string::npos) << text;
}

TEST(SsdTrainTest, RgbTrainingNeedsNoStereoFiles) {
  const fs::path root = WriteTinyDataset("rgb_data", 2);
  fs::remove_all(root / "training/image_3");
  fs::remove_all(root / "training/calib");
  TrainSsdOptions options = TinyTraining(root, ModelsTestDir("rgb_model"));
  options.model.encoding = InputEncoding::kRgb;
  options.epochs = 1;
  EXPECT_EQ(TrainSsd(options).epochs_done, 1);
  // --resume with a model but no checkpoint has nothing to resume: refused, not trained over.
  fs::remove(options.out_dir / "checkpoint.pt");
  const std::string weights = ReadFile(options.out_dir / "model.pt");
  TrainSsdOptions resume = options;
  resume.resume = true;
  try {
    TrainSsd(resume);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("but no checkpoint.pt to resume from"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadFile(options.out_dir / "model.pt"), weights);
  // --force trains a new model over it (another seed: other weights), its log restarted.
  TrainSsdOptions force = options;
  force.force = true;
  force.seed = 2;
  EXPECT_EQ(TrainSsd(force).epochs_done, 1);
  EXPECT_NE(ReadFile(options.out_dir / "model.pt"), weights);
  EXPECT_EQ(CountLines(options.out_dir / "train_log.csv"), 2);
  EXPECT_NO_THROW(SsdModel::Load(options.out_dir));
  force.resume = true;
  EXPECT_THROW(TrainSsd(force), std::invalid_argument);  // the two exclude each other
  // ... but RGB-H does, and says which are missing.
  options.model.encoding = InputEncoding::kRgbhFixed;
  options.out_dir = ModelsTestDir("rgbh_model");
  try {
    TrainSsd(options);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("image_3"), std::string::npos) << e.what();
  }
}

TEST(SsdTrainTest, ResumeRefusesACheckpointOfAnotherFolder) {
  // The audit's model.pt case, for checkpoint.pt: another training's checkpoint of the same shapes
  // copied in would resume silently from the other run's weights.
  const fs::path root = WriteTinyDataset("tied_data", 2);
  TrainSsdOptions a = TinyTraining(root, ModelsTestDir("tied_a"));
  a.model.encoding = InputEncoding::kRgb;
  a.epochs = 2;
  a.max_epochs_this_run = 1;
  TrainSsdOptions b = a;
  b.out_dir = ModelsTestDir("tied_b");
  EXPECT_EQ(TrainSsd(a).epochs_done, 1);
  EXPECT_EQ(TrainSsd(b).epochs_done, 1);
  fs::copy_file(b.out_dir / "checkpoint.pt", a.out_dir / "checkpoint.pt",
                fs::copy_options::overwrite_existing);
  const std::string weights = ReadFile(a.out_dir / "model.pt");
  a.resume = true;
  try {
    TrainSsd(a);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((a.out_dir / "checkpoint.pt").string() +
                                         " is from another training run ("),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ReadFile(a.out_dir / "model.pt"), weights);  // nothing trained over
  // Its own checkpoint resumes, and the resumed run keeps the folder's id.
  b.resume = true;
  b.max_epochs_this_run = 0;
  const std::string run_b = ReadWeightsRecord(ReadFile(b.out_dir / "model.json"), "b").training_run;
  EXPECT_EQ(run_b.size(), 16u);
  EXPECT_EQ(TrainSsd(b).epochs_done, 2);
  EXPECT_EQ(ReadWeightsRecord(ReadFile(b.out_dir / "model.json"), "b").training_run, run_b);
  EXPECT_NE(ReadWeightsRecord(ReadFile(a.out_dir / "model.json"), "a").training_run, run_b);
}

// Shards of a real model's detection, merged, are the folder of one run byte for byte (run.json
// but its command line). 5 frames in batches of 3 in 2 shards: shard 0 is frames 0-2 (the one
// run's first batch), not 0-1 as frame shards would be (then frame 0's scores differed from the
// one run's in the sixth decimal: LibTorch's floats depend on the batch size).
TEST(DetectSsdShardTest, MergedShardsAreOneRunByteForByte) {
  const fs::path root = WriteTinyDataset("shard_data", 5);
  TrainSsdOptions training = TinyTraining(root, ModelsTestDir("shard_model"));
  training.epochs = 1;
  TrainSsd(training);
  DetectSsdOptions detect;
  detect.model_dir = training.out_dir;
  detect.data_root = root;
  detect.threads = 1;
  detect.batch_size = 3;
  detect.decode.score_threshold = 0.0;  // every box: many scores, compared to the last digit
  detect.progress.stream = nullptr;
  detect.out_dir = ModelsTestDir("shard_one");
  detect.command_line = "the command line";
  EXPECT_EQ(DetectSsd(detect).frames, 5);
  MergeDetectionsOptions merge;
  for (int k : {1, 0}) {
    DetectSsdOptions shard = detect;
    shard.shard = {k, 2};
    shard.out_dir = ModelsTestDir("shard_" + std::to_string(k));
    EXPECT_EQ(DetectSsd(shard).frames, k == 0 ? 3 : 2);
    EXPECT_TRUE(fs::exists(shard.out_dir / kDetectShardFile));
    merge.shards.push_back(shard.out_dir);
  }
  merge.out_dir = ModelsTestDir("shard_merged");
  merge.command_line = detect.command_line;
  EXPECT_EQ(MergeDetections(merge).frames, 5);
  int files = 0;
  for (const auto& e : fs::directory_iterator(detect.out_dir)) {
    const fs::path merged = merge.out_dir / e.path().filename();
    ASSERT_TRUE(fs::exists(merged)) << merged;
    EXPECT_EQ(ReadFile(merged), ReadFile(e.path())) << merged;
    ++files;
  }
  EXPECT_EQ(files, 6);  // five frames and run.json
  EXPECT_GT(fs::file_size(detect.out_dir / (FrameId(4) + ".txt")), 100u);  // not vacuous
  EXPECT_FALSE(fs::exists(merge.out_dir / kDetectShardFile));
}

}  // namespace
}  // namespace stereodet
