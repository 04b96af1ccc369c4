// End to end on tiny KITTI-format frames written by the test: the two-stage detector overfits a
// few frames and finds their boxes, training is deterministic and resumes bit-identically, RGB-D
// trains from stereo and mirrors an RGB model, detect writes KITTI files.
#include "stereodet/models/rpn/rpn_train.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "stereodet/geometry/calibration.h"
#include "stereodet/geometry/iou.h"
#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/models_test_util.h"
#include "stereodet/models/rpn/rpn_detect.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// Frames of 256 x 128 px, one car per frame at its own place and size (WriteTinyImageDataset).
fs::path WriteTinyDataset(const std::string& name, int frames) {
  return WriteTinyImageDataset(name, frames, {256, 128}, 60, 170, [](int i) {
    return cv::Rect(30 + 50 * i, 40 + 6 * i, 72 - 8 * i, 44 - 4 * i);
  });
}

TrainRpnOptions TinyTraining(const fs::path& root, const fs::path& out) {
  TrainRpnOptions o = TinyTrainingOptions<TrainRpnOptions>(root, out);
  o.model.input_width = 128;
  o.model.input_height = 64;
  o.model.image_width = 8;
  o.model.geometry_width = 8;
  o.model.blocks_per_stage = 1;
  o.model.head_channels = 64;
  o.model.pooled_size = 4;
  o.model.anchors.sizes_px = {16, 32};
  o.batch_size = 3;
  o.learning_rate = 3e-3;
  o.warmup_steps = 5;
  o.data.augment = false;
  o.data.stereo.disparity.num_disparities = 32;
  o.data.stereo.ground.enabled = false;
  o.trainer.anchors.samples_per_image = 64;
  o.trainer.rois.samples_per_image = 32;
  o.trainer.proposals.pre_nms_top_n = 200;
  o.trainer.proposals.post_nms_top_n = 50;
  return o;
}

std::string WithoutTimes(const std::string& log) {  // the CSV without its two timing columns
  std::string kept;
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    kept += line.substr(0, line.rfind(',', line.rfind(',') - 1)) + "\n";
  }
  return kept;
}

TEST(RpnTrainTest, OverfitsAFewFramesAndDetectsItsOwnBoxes) {
  const fs::path root = WriteTinyDataset("rpn_data", 3);
  const fs::path out = ModelsTestDir("rpn_model");
  TrainRpnOptions options = TinyTraining(root, out);
  options.epochs = 150;
  options.learning_rate = 5e-3;
  options.trainer.rois.samples_per_image = 16;
  options.trainer.rois.foreground_fraction = 0.5;
  const TrainRpnSummary s = TrainRpn(options);
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.objects, 3);
  EXPECT_EQ(s.epochs_done, 150);
  EXPECT_GT(s.parameters, s.image_branch_parameters);
  EXPECT_EQ(s.geometry_branch_parameters, 0);

  const DetectRpnOptions d = TinyDetectOptions<DetectRpnOptions>(out, root, root / "detections");
  const DetectSummary ds = DetectRpn(d);
  EXPECT_EQ(ds.frames, 3);
  EXPECT_TRUE(fs::exists(d.out_dir / "run.json"));
  int found = 0;
  for (int i = 0; i < 3; ++i) {
    const std::string id = FrameId(i);
    const Object label = TinyLabels(root, id).at(0);
    const double best =
        BestConfidentOverlap(TinyDetections(d.out_dir, id), 0.5, [&](const Object& det) {
          EXPECT_EQ(det.type, "Car") << "a confident detection of another class";
          return Iou2D(det.box, label.box);
        });
    // IoU 0.5 (KITTI's loose overlap), not tighter: the tiny head's boxes land at IoU 0.59-0.7
    // depending on the BLAS kernels of the CPU (measured 0.5897 on one frame of an AMD EPYC with
    // OpenBLAS; the test passed at 0.6 on the earlier Intel VMs), while an untrained or broken
    // model stays far below.
    EXPECT_GT(best, 0.5) << "frame " << id << ": no confident detection of its car\n"
                         << ReadFile(out / "train_log.csv");
    found += best > 0.5;
  }
  EXPECT_EQ(found, 3);  // recall 1 on the training frames
}

// A sample is a function of its frame and seed only: the same twice, whatever was sampled between,
// and a flipped sample mirrors the image and the geometry together. (A flip once mirrored the
// frame's stored depth and height codes in place: every later sample of the frame had its
// geometry mirrored against its image until the next flip.)
TEST(RpnTrainTest, SamplesNeverChangeTheStoredGeometry) {
  const std::filesystem::path dir = ModelsTestDir("rpn_sample_geometry");
  RpnConfig config;
  config.input = RpnInput::kRgbd;
  config.input_width = 64;
  config.input_height = 32;
  RpnFrame frame;
  frame.id = "000000";
  frame.image_path = dir / "000000.png";
  cv::Mat image(32, 64, CV_8UC3);
  for (int v = 0; v < 32; ++v) {
    for (int u = 0; u < 64; ++u) image.at<cv::Vec3b>(v, u) = cv::Vec3b(4 * u, 2 * v, 100);
  }
  ASSERT_TRUE(cv::imwrite(frame.image_path.string(), image));
  // Codes that grow to the right: a mirrored one is told apart at once.
  frame.depth_code.create(32, 64, CV_16UC1);
  frame.height_code.create(32, 64, CV_16UC1);
  for (int v = 0; v < 32; ++v) {
    for (int u = 0; u < 64; ++u) {
      frame.depth_code.at<uint16_t>(v, u) = static_cast<uint16_t>(1000 * (u + 1));
      frame.height_code.at<uint16_t>(v, u) = static_cast<uint16_t>(5 * (u + 1));
    }
  }
  const cv::Mat stored_depth = frame.depth_code.clone();
  RpnDataOptions options;
  options.colour.brightness = options.colour.contrast = options.colour.saturation = 0;
  const RpnTrainingData data({frame}, config, options);
  // Whether a channel range of a sample grows to the left (the stored frame grows to the right).
  auto mirrored = [](const RpnSample& s, int first, int last) {
    float left = 0, right = 0;
    for (int c = first; c <= last; ++c) {
      left += s.input.At(c, 10, 0);
      right += s.input.At(c, 10, 63);
    }
    return left > right;
  };
  int flipped = 0, kept = 0;
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    const RpnSample a = data.Sample(0, seed);
    const RpnSample b = data.Sample(0, seed);
    EXPECT_EQ(a.input.data, b.input.data) << "seed " << seed;
    // Colour (channels 0-2) and depth and height (3, 4) mirrored together, or neither.
    const bool image_flipped = mirrored(a, 0, 2);
    EXPECT_EQ(image_flipped, mirrored(a, 3, 3)) << "seed " << seed;
    EXPECT_EQ(image_flipped, mirrored(a, 4, 4)) << "seed " << seed;
    (image_flipped ? flipped : kept) += 1;
  }
  EXPECT_GT(flipped, 0);
  EXPECT_GT(kept, 0);
  EXPECT_EQ(cv::countNonZero(frame.depth_code != stored_depth), 0);
}

TEST(RpnTrainTest, DeterministicAndResumeIsBitIdentical) {
  const fs::path root = WriteTinyDataset("rpn_resume_data", 2);
  const fs::path out = ModelsTestDir("rpn_resume");
  TrainRpnOptions options = TinyTraining(root, out);
  options.data.augment = true;  // seeded per (seed, epoch, frame): resumes exactly
  options.batch_size = 1;
  options.epochs = 3;
  options.max_epochs_this_run = 1;
  EXPECT_EQ(TrainRpn(options).epochs_done, 1);
  options.max_epochs_this_run = 0;
  EXPECT_THROW(TrainRpn(options), std::invalid_argument);  // a model there, no --resume
  options.resume = true;
  TrainRpnOptions other_input = options;  // --resume takes model.json's config, of its input
  other_input.model.input = RpnInput::kRgbd;
  try {
    TrainRpn(other_input);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--resume: " + (out / "model.json").string() +
                                         " was trained with --input rgb, not rgbd"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(TrainRpn(options).epochs_run, 2);

  std::vector<fs::path> straight;
  for (const char* name : {"rpn_straight_a", "rpn_straight_b"}) {
    straight.push_back(ModelsTestDir(name));
    TrainRpnOptions direct = TinyTraining(root, straight.back());
    direct.data.augment = true;
    direct.batch_size = 1;
    direct.epochs = 3;
    TrainRpn(direct);
  }
  // The checkpoint is tied to its training run, as the other families' are: one copied from
  // another folder is refused before anything is loaded or written.
  const std::string own_checkpoint = ReadFile(out / "checkpoint.pt");
  const std::string model_json = ReadFile(out / "model.json");
  EXPECT_NE(model_json.find("\"training_run\": \""), std::string::npos);
  fs::copy_file(straight[0] / "checkpoint.pt", out / "checkpoint.pt",
                fs::copy_options::overwrite_existing);
  EXPECT_THAT([&] { TrainRpn(options); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  ::testing::HasSubstr("checkpoint.pt is from another training run (")));
  EXPECT_EQ(ReadFile(out / "model.json"), model_json);
  WriteFileAtomically(out / "checkpoint.pt", own_checkpoint);

  // Two uninterrupted runs and the resumed one: the same losses at every epoch ...
  const std::string log = WithoutTimes(ReadFile(out / "train_log.csv"));
  EXPECT_EQ(log, WithoutTimes(ReadFile(straight[0] / "train_log.csv")));
  EXPECT_EQ(log, WithoutTimes(ReadFile(straight[1] / "train_log.csv")));
  // ... and the same weights (compared by what they compute, bit for bit: LibTorch's archive
  // bytes differ run to run).
  const RpnModel a = RpnModel::Load(out), b = RpnModel::Load(straight[0]);
  const RpnTrainingData data(KittiDataset(root), {FrameId(1)}, a.config(),
                             TinyTraining(root, out).data);
  const RpnSample sample = data.Sample(0, 1);
  RpnDetectOptions all;
  all.decode.score_threshold = 0.0f;
  const auto pa = a.Propose({sample.input}, all.proposals),
             pb = b.Propose({sample.input}, all.proposals);
  ASSERT_FALSE(pa[0].empty());
  ASSERT_EQ(pa[0].size(), pb[0].size());
  for (size_t i = 0; i < pa[0].size(); ++i) {
    EXPECT_EQ(pa[0][i].box, pb[0][i].box) << i;
    EXPECT_EQ(pa[0][i].score, pb[0][i].score) << i;
  }
  const auto da = a.Detect({sample.input}, all), db = b.Detect({sample.input}, all);
  ASSERT_EQ(da[0].size(), db[0].size());
  for (size_t i = 0; i < da[0].size(); ++i) {
    EXPECT_EQ(da[0][i], db[0][i]) << i;
  }
}

TEST(RpnTrainTest, RgbdTrainsFromStereoMirrorsAnRgbModelAndDetects) {
  const fs::path root = WriteTinyDataset("rpn_rgbd_data", 2);
  const fs::path rgb_out = ModelsTestDir("rpn_rgb_for_init");
  TrainRpnOptions rgb = TinyTraining(root, rgb_out);
  rgb.epochs = 1;
  TrainRpn(rgb);

  const fs::path out = ModelsTestDir("rpn_rgbd");
  TrainRpnOptions options = TinyTraining(root, out);
  options.model.input = RpnInput::kRgbd;
  options.epochs = 1;
  options.init_from = rgb_out;
  options.init_geometry = true;
  const TrainRpnSummary s = TrainRpn(options);
  EXPECT_EQ(s.frames, 2);
  EXPECT_GT(s.init_tensors, 0);
  EXPECT_EQ(s.geometry_branch_parameters, s.image_branch_parameters);
  EXPECT_GT(s.parameters, s.image_branch_parameters + s.geometry_branch_parameters);
  // The stereo settings are recorded for detection.
  EXPECT_NE(ReadFile(out / "model.json").find("\"num_disparities\": 32"), std::string::npos);
  // --init-from an rgbd model is refused.
  TrainRpnOptions again = options;
  again.out_dir = ModelsTestDir("rpn_rgbd_from_rgbd");
  again.init_from = out;
  EXPECT_THROW(TrainRpn(again), std::invalid_argument);

  DetectRpnOptions d = TinyDetectOptions<DetectRpnOptions>(out, root, root / "detections");
  d.blur_sigma_px = 2.0;
  const DetectSummary ds = DetectRpn(d);
  EXPECT_EQ(ds.frames, 2);
  EXPECT_TRUE(fs::exists(d.out_dir / (FrameId(1) + ".txt")));
  EXPECT_NE(ReadFile(d.out_dir / "run.json").find("\"blur_sigma_px\": 2"), std::string::npos);
  // Detecting into the model folder is refused.
  d.out_dir = out / "det";
  EXPECT_THROW(DetectRpn(d), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
