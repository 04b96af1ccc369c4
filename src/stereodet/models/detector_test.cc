// Detector (detector.h) on every committed model: frames held in memory give, object for object,
// what the batch command (`detect ssd|rpn|det3d`, written to files) gives for the same frames.
// The frames: a fresh synthetic set with LiDAR and its stereo points, made by the CTest fixture
// models.detector_data (BIN/detector_data, BIN/detector_points).
#include "stereodet/models/detector.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/models/det3d/det3d_detect.h"
#include "stereodet/models/rpn/rpn_detect.h"
#include "stereodet/models/ssd/ssd_detect.h"
#include "stereodet/models/train_common.h"
#include "stereodet/stereo/image_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

fs::path DataDir() { return TestBinaryDir() / "detector_data"; }
fs::path PointsDir() { return TestBinaryDir() / "detector_points"; }

// Every committed model folder (models/NAME with model.pt).
std::vector<fs::path> CommittedModels() {
  std::vector<fs::path> dirs;
  for (const fs::directory_entry& e : fs::directory_iterator(TestSourceDir() / "models")) {
    // A training still running in the checkout (its run.json has fewer epochs done than asked)
    // rewrites model.pt at every epoch: not a model to compare two runs of.
    if (e.is_directory() && fs::exists(e.path() / "model.pt") &&
        UnfinishedTrainingWarning(e.path()).empty()) {
      dirs.push_back(e.path());
    }
  }
  std::sort(dirs.begin(), dirs.end());
  return dirs;
}

// The frames of the fixture's split, in memory: both images, the calibration, the LiDAR scan for
// LiDAR models or the stereo points for stereo ones (as `detect det3d --points` reads them).
std::vector<StereoFrame> LoadFrames(const Detector& detector) {
  const KittiDataset dataset(DataDir());
  std::vector<StereoFrame> frames;
  for (const std::string& id : dataset.ReadSplit("val")) {
    const FramePaths paths = dataset.Paths(id);
    StereoFrame frame;
    frame.id = id;
    frame.left = ReadColourImage(paths.image_left);
    frame.right = ReadColourImage(paths.image_right);
    frame.calib = ReadCalibration(paths.calib);
    if (detector.family() == "det3d") {
      frame.points = ReadVelodyne(
          detector.input() == "lidar" ? paths.velodyne : PointsDir() / "velodyne" / (id + ".bin"));
    }
    frames.push_back(std::move(frame));
  }
  return frames;
}

// The options every family's batch command shares, for `model`, `batch_size` frames a pass.
template <typename Options>
Options BatchOptions(const fs::path& model, int batch_size, const fs::path& out) {
  Options o;
  o.model_dir = model;
  o.data_root = DataDir();
  o.out_dir = out;
  o.batch_size = batch_size;
  o.threads = 2;
  o.progress.stream = nullptr;
  return o;
}

// The batch command's detection folder for `model`, `batch_size` frames a forward pass.
fs::path RunBatchCommand(const fs::path& model, const std::string& family, int batch_size,
                         const fs::path& out) {
  if (family == "ssd") {
    DetectSsd(BatchOptions<DetectSsdOptions>(model, batch_size, out));
  } else if (family == "rpn") {
    DetectRpn(BatchOptions<DetectRpnOptions>(model, batch_size, out));
  } else {
    DetectDet3dOptions o = BatchOptions<DetectDet3dOptions>(model, batch_size, out);
    o.points_dir = PointsDir();
    DetectDet3d(o);
  }
  return out;
}

// A frame's objects as the batch command writes them (the same text, so the same rounding).
std::string AsFileText(const std::vector<Object>& objects) {
  const TestTempDir dir("as-file");
  WriteObjects(dir / "x.txt", objects);
  return ReadFile(dir / "x.txt");
}

TEST(DetectorTest, EveryCommittedModelInMemoryGivesTheBatchCommandsObjects) {
  const std::vector<fs::path> models = CommittedModels();
  ASSERT_GE(models.size(), 6u) << "the committed models are missing";
  ASSERT_TRUE(fs::exists(DataDir())) << "run the fixture models.detector_data first";
  for (const fs::path& model : models) {
    SCOPED_TRACE(model.filename().string());
    DetectorOptions options;
    options.threads = 2;
    Detector detector = Detector::Open(model, options);
    const std::vector<StereoFrame> frames = LoadFrames(detector);
    ASSERT_GE(frames.size(), 3u);
    // One frame at a time, as the command with batches of one.
    const TestTempDir out("batch");
    RunBatchCommand(model, detector.family(), 1, out / "one");
    int objects = 0;
    for (const StereoFrame& frame : frames) {
      const DetectResult result = detector.Detect(frame);
      EXPECT_EQ(result.id, frame.id);
      EXPECT_EQ(AsFileText(result.objects), ReadFile(out / "one" / (frame.id + ".txt")))
          << "frame " << frame.id;
      EXPECT_GT(result.times.network_s, 0.0);
      objects += static_cast<int>(result.objects.size());
    }
    EXPECT_GT(objects, 0) << "no object to compare";
    // All frames in one batch, as the command with that batch size.
    RunBatchCommand(model, detector.family(), static_cast<int>(frames.size()), out / "all");
    const std::vector<DetectResult> batch = detector.DetectBatch(frames);
    ASSERT_EQ(batch.size(), frames.size());
    for (size_t i = 0; i < frames.size(); ++i) {
      EXPECT_EQ(batch[i].id, frames[i].id);
      EXPECT_EQ(AsFileText(batch[i].objects), ReadFile(out / "all" / (frames[i].id + ".txt")))
          << "frame " << frames[i].id << " in a batch";
    }
  }
}

TEST(DetectorTest, AFrameWithoutWhatTheModelNeedsIsRefusedNamingIt) {
  Detector rgbh = Detector::Open(TestSourceDir() / "models" / "ssd-rgbh-learned");
  EXPECT_EQ(rgbh.family(), "ssd");
  EXPECT_EQ(rgbh.input(), "rgbh-learned");
  EXPECT_TRUE(rgbh.needs().right_image);
  ASSERT_TRUE(rgbh.stereo().has_value());
  StereoFrame frame;
  frame.id = "000042";
  frame.left = cv::Mat(375, 1242, CV_8UC3, cv::Scalar::all(100));
  EXPECT_THAT([&] { rgbh.Detect(frame); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr(
                  "frame 000042: " + (TestSourceDir() / "models" / "ssd-rgbh-learned").string() +
                  " (ssd rgbh-learned) needs the right image; the frame has none")));
  frame.right = frame.left.clone();
  EXPECT_THAT([&] { rgbh.Detect(frame); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("needs a calibration")));

  Detector lidar = Detector::Open(TestSourceDir() / "models" / "det3d-lidar");
  EXPECT_EQ(lidar.family(), "det3d");
  EXPECT_TRUE(lidar.needs().points);
  StereoFrame no_points;
  no_points.image_size = cv::Size(1242, 375);
  no_points.calib = Calibration();
  EXPECT_THAT([&] { lidar.Detect(no_points); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("needs the LiDAR points")));
  // A stereo 3D model reads the pair unless the frame carries its points.
  Detector stereo = Detector::Open(TestSourceDir() / "models" / "det3d-stereo");
  EXPECT_TRUE(stereo.needs().left_image && stereo.needs().right_image);
  EXPECT_FALSE(stereo.needs().points);
  EXPECT_THAT([&] { stereo.Detect(no_points); },
              ::testing::ThrowsMessage<std::invalid_argument>(HasSubstr("needs the left image")));
  // A batch prepared by one detector is refused by another.
  Detector rgb = Detector::Open(TestSourceDir() / "models" / "ssd-rgb");
  frame.calib.reset();
  EXPECT_THROW(rgbh.Run(rgb.Prepare({frame})), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
