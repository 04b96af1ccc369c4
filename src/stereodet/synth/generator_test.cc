#include "stereodet/synth/generator.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/kitti/plane_io.h"
#include "stereodet/kitti/velodyne_io.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

// Small and fast: 160 x 48 images and a coarse LiDAR.
SynthOptions TinyOptions() {
  SynthOptions options;
  options.width = 160;
  options.height = 48;
  options.lidar_options.azimuth_step_deg = 1.0;
  return options;
}

TEST(GeneratorTest, FramesAreDeterministicAndDifferBySeed) {
  const SynthOptions options = TinyOptions();
  const SynthFrame a = GenerateFrame(options, 3, 1);
  const SynthFrame b = GenerateFrame(options, 3, 1);
  const SynthFrame c = GenerateFrame(options, 4, 1);
  EXPECT_EQ(cv::norm(a.image_left, b.image_left, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.scan, b.scan);
  EXPECT_GT(cv::norm(a.image_left, c.image_left, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.image_left.size(), cv::Size(160, 48));
  EXPECT_FALSE(a.scan.empty());
}

TEST(GeneratorTest, LabelsAreKittiLike) {
  SynthOptions options = TinyOptions();
  options.width = 621;  // half resolution: labels scale their pixel thresholds
  options.height = 188;
  int labelled = 0;
  for (int i = 0; i < 4; ++i) {
    const SynthFrame f = GenerateFrame(options, 9, i);
    for (const Object& o : f.labels) {
      if (o.IsDontCare()) continue;
      ++labelled;
      EXPECT_GE(o.truncated, 0.0);
      EXPECT_LE(o.truncated, 1.0);
      EXPECT_GE(o.occluded, 0);
      EXPECT_LE(o.occluded, 3);
      EXPECT_GE(o.box.left, 0.0);
      EXPECT_LE(o.box.right, options.width - 1.0);
      EXPECT_LT(o.box.left, o.box.right);
      EXPECT_GT(o.box3d.h, 0.0);
      const Eigen::Vector3d& x = o.box3d.location;  // on the road or sidewalk
      EXPECT_NEAR(x.y(), f.scene.GroundY(static_cast<float>(x.x()), static_cast<float>(x.z())),
                  0.2);
      EXPECT_NEAR(o.alpha, AlphaFromRotationY(o.box3d.rotation_y, o.box3d.location), 0.006);
    }
  }
  EXPECT_GT(labelled, 4);
}

TEST(GeneratorTest, DatasetRoundTripsThroughTheKittiModule) {
  const TestTempDir dir;
  DatasetOptions options;
  options.out = dir.path();
  options.frames = 2;
  options.seed = 5;
  options.threads = 1;
  options.progress.stream = nullptr;
  options.synth = TinyOptions();
  const DatasetSummaryLine summary = GenerateDataset(options);
  EXPECT_EQ(summary.generated, 2);
  EXPECT_EQ(summary.train + summary.val, 2);
  EXPECT_EQ(summary.val, 1);

  const KittiDataset dataset(dir.path());
  EXPECT_EQ(dataset.ListIds(), (std::vector<std::string>{"000000", "000001"}));
  EXPECT_EQ(dataset.ReadSplit("train").size() + dataset.ReadSplit("val").size(), 2u);
  const SynthFrame frame = GenerateFrame(options.synth, 5, 1);
  const FramePaths paths = dataset.Paths("000001");
  EXPECT_EQ(ReadObjects(paths.label).objects, frame.labels);
  const Calibration calib = ReadCalibration(paths.calib);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(calib.projection[i], frame.calib.projection[i]);
  EXPECT_TRUE(calib.cam0_from_velo.isApprox(frame.calib.cam0_from_velo, 1e-15));
  EXPECT_EQ(ReadVelodyne(paths.velodyne), frame.scan);
  const cv::Mat left = cv::imread(paths.image_left.string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(left, frame.image_left, cv::NORM_INF), 0.0);
  const cv::Mat disparity = cv::imread(paths.disparity.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(disparity.type(), CV_16UC1);
  EXPECT_LE(cv::norm(DecodeKittiDisparity(disparity), frame.disparity, cv::NORM_INF),
            0.5 / 256 + 1e-6);

  // Resuming skips complete frames and redoes a missing file's frame.
  fs::remove(paths.velodyne);
  const DatasetSummaryLine again = GenerateDataset(options);
  EXPECT_EQ(again.skipped, 1);
  EXPECT_EQ(again.generated, 1);
  EXPECT_EQ(ReadVelodyne(paths.velodyne), frame.scan);
  // ... but refuses other settings.
  options.seed = 6;
  EXPECT_THROW(GenerateDataset(options), std::invalid_argument);
}

// The planes file holds the least-squares plane of the true ground (TrueGroundPlane), which is
// tilted by the car's pitch and roll; the scan's ground returns lie on the true ground (within the
// range noise), nothing lies below it, and the labelled objects stand on it (road) or on a kerb
// above it. A missing planes file makes its frame be redone. Without road shapes the plane is
// the flat ground's.
TEST(GeneratorTest, PlanesFileHoldsTheGroundTheScanAndLabelsStandOn) {
  const TestTempDir dir;
  DatasetOptions options;
  options.out = dir.path();
  options.frames = 1;
  options.seed = 8;
  options.threads = 1;
  options.progress.stream = nullptr;
  options.synth = TinyOptions();
  GenerateDataset(options);
  const FramePaths paths = KittiDataset(dir.path()).Paths("000000");
  const Eigen::Vector4d plane = ReadGroundPlane(paths.planes);
  const SynthFrame frame = GenerateFrame(options.synth, 8, 0);
  const Eigen::Vector4d truth =
      TrueGroundPlane(frame.scene, frame.calib, options.synth.width, options.synth.height);
  EXPECT_NEAR((plane - truth).norm(), 0.0, 1e-6);  // seven digits
  EXPECT_GT(plane.head<3>().dot(Eigen::Vector3d(0.0, -1.0, 0.0)), std::cos(2.0 * M_PI / 180.0));
  EXPECT_GT(std::abs(plane[3] - 1.65), 1e-4) << "this frame's camera height is jittered";
  const Eigen::Affine3d rect_from_velo = frame.calib.RectFromVelo();
  const auto above_ground = [&](const Eigen::Vector3d& x) {
    return frame.scene.GroundY(static_cast<float>(x.x()), static_cast<float>(x.z())) - x.y();
  };
  int on_ground = 0;
  for (const VeloPoint& p : frame.scan) {
    const double height = above_ground(rect_from_velo * Eigen::Vector3d(p.x, p.y, p.z));
    EXPECT_GT(height, -0.1) << "a return below the ground";
    on_ground += std::abs(height) < 0.06;
  }
  EXPECT_GT(on_ground, static_cast<int>(frame.scan.size()) / 5);
  for (const Object& o : frame.labels) {
    if (o.type == "DontCare") continue;
    const double height = above_ground(o.box3d.location);
    EXPECT_GE(height, -0.006);  // two-decimal labels
    EXPECT_LE(height, 0.2);     // a kerb at most
  }
  SynthOptions flat = options.synth;
  flat.scene.road_shapes = false;
  const SynthFrame flat_frame = GenerateFrame(flat, 8, 0);
  EXPECT_EQ(flat_frame.ground_plane, Eigen::Vector4d(0.0, -1.0, 0.0, flat_frame.scene.ground_y_m));
  fs::remove(paths.planes);
  const DatasetSummaryLine again = GenerateDataset(options);
  EXPECT_EQ(again.generated, 1);
  EXPECT_EQ(ReadGroundPlane(paths.planes), plane);
}

// A folder written by another version of the scene model (here: version 1, before issue 16's
// textures) is refused, and the message names the setting that differs.
TEST(GeneratorTest, RefusesAFolderOfAnotherVersionNamingTheSetting) {
  const TestTempDir dir("old");
  DatasetOptions options;
  options.out = dir.path();
  options.frames = 1;
  options.seed = 3;
  options.progress.stream = nullptr;
  options.synth = TinyOptions();
  std::string line = "seed=3 " + options.synth.Fingerprint() + "\n";
  const size_t at = line.find("version=");
  ASSERT_NE(at, std::string::npos);
  const size_t end = line.find(' ', at);
  ASSERT_NE(line.substr(at, end - at), "version=1");
  line.replace(at, end - at, "version=1");
  fs::create_directories(dir.path());
  std::ofstream(dir.path() / "synth_settings.txt") << line;
  try {
    GenerateDataset(options);
    ADD_FAILURE() << "a version-1 folder was not refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("version: 1 in the folder"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "training" / "image_2" / "000000.png"));
}

TEST(GeneratorTest, SameSeedSameBytesWithOneAndTwoThreads) {
  const TestTempDir one("one"), two("two");
  DatasetOptions options;
  options.frames = 3;
  options.seed = 17;
  options.progress.stream = nullptr;
  options.synth = TinyOptions();
  options.out = one.path();
  options.threads = 1;
  GenerateDataset(options);
  options.out = two.path();
  options.threads = 2;
  GenerateDataset(options);
  int files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(one.path())) {
    if (!entry.is_regular_file()) continue;
    const fs::path relative = fs::relative(entry.path(), one.path());
    ASSERT_TRUE(fs::exists(two.path() / relative)) << relative;
    EXPECT_EQ(ReadFile(entry.path()), ReadFile(two.path() / relative)) << relative;
    ++files;
  }
  EXPECT_EQ(files, 3 * 7 + 3 + 1);  // seven files a frame (planes/ since issue 16), three splits,
                                    // the settings
}

TEST(GeneratorTest, ValFramesAreExactAndStable) {
  const std::vector<int> val = ValFrames(10, 0.3, 1);
  EXPECT_EQ(val.size(), 3u);
  EXPECT_TRUE(std::is_sorted(val.begin(), val.end()));
  EXPECT_EQ(val, ValFrames(10, 0.3, 1));
  EXPECT_TRUE(ValFrames(10, 0.0, 1).empty());
  EXPECT_EQ(ValFrames(10, 1.0, 1).size(), 10u);
}

TEST(GeneratorTest, RejectsBadOptions) {
  DatasetOptions options;
  EXPECT_THROW(options.Check(), std::invalid_argument);  // no output folder
  options.out = "x";
  options.val_fraction = 1.5;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  SynthOptions synth;
  synth.width = 4;
  EXPECT_THROW(synth.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
