#include "stereodet/realtime/frame_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// KITTI's calibration of frame 000000 (principal point 609.6, 172.9 px: it fits 1242 x 375).
fs::path KittiCalib() {
  return TestSourceDir() / "tests/data/kitti_mini/training/calib/000000.txt";
}

cv::Mat Image(int width, int height, int value) {
  return cv::Mat(height, width, CV_8UC3, cv::Scalar(value, value / 2, 255 - value));
}

std::string Name(int i) { return "frame_" + std::to_string(i) + ".png"; }

void WriteImage(const fs::path& path, const cv::Mat& image) {
  fs::create_directories(path.parent_path());
  ASSERT_TRUE(cv::imwrite(path.string(), image)) << path;
}

TEST(FrameSourceTest, SequenceFilesAreSortedImagesOfAFolderOrAGlob) {
  TestTempDir dir;
  for (const char* name : {"b.png", "a.png", "c.jpg"})
    WriteImage(dir.path() / name, Image(8, 4, 9));
  std::ofstream(dir.path() / "notes.txt") << "not an image";
  EXPECT_EQ(
      SequenceFiles(dir.path().string()),
      (std::vector<fs::path>{dir.path() / "a.png", dir.path() / "b.png", dir.path() / "c.jpg"}));
  EXPECT_EQ(SequenceFiles((dir.path() / "*.png").string()),
            (std::vector<fs::path>{dir.path() / "a.png", dir.path() / "b.png"}));
  try {
    SequenceFiles((dir.path() / "*.bmp").string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("no image files in"));
  }
}

TEST(FrameSourceTest, SequenceGivesFramesInOrderAndReportsWhatAFrameLacks) {
  TestTempDir dir;
  for (int i = 0; i < 3; ++i) WriteImage(dir.path() / "l" / Name(i), Image(1242, 375, 10 * i));
  WriteImage(dir.path() / "r" / Name(0), Image(1242, 375, 1));
  WriteImage(dir.path() / "r" / Name(1), Image(1240, 375, 2));  // another size
  FrameSourceOptions options;
  options.left = (dir.path() / "l").string();
  options.right = (dir.path() / "r").string();
  options.calib = KittiCalib();
  options.needs.right_image = options.needs.calibration = true;
  const std::unique_ptr<FrameSource> source = OpenFrameSource(options);
  EXPECT_EQ(source->size(), 3);
  EXPECT_EQ(source->fps(), 10.0);  // KITTI's rate unless --fps
  std::vector<SourceFrame> frames;
  while (std::optional<SourceFrame> f = source->Next()) frames.push_back(std::move(*f));
  ASSERT_EQ(frames.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(frames[i].index, i);
    EXPECT_EQ(frames[i].frame.id, "frame_" + std::to_string(i));
    EXPECT_DOUBLE_EQ(frames[i].frame.timestamp_s, i / 10.0);
  }
  EXPECT_EQ(frames[0].error, "");
  EXPECT_EQ(frames[0].frame.left.size(), cv::Size(1242, 375));
  EXPECT_EQ(frames[0].frame.right.size(), cv::Size(1242, 375));
  ASSERT_TRUE(frames[0].frame.calib.has_value());
  EXPECT_THAT(frames[1].error, HasSubstr("a stereo pair must have equal sizes"));
  EXPECT_THAT(frames[1].error, HasSubstr("frame_1.png is 1240x375 px"));
  EXPECT_THAT(frames[2].error, HasSubstr("no right image for"));
  // Users read these in run's JSON Lines: the failed checks' source tags are left out.
  for (const int i : {1, 2}) EXPECT_THAT(frames[i].error, ::testing::Not(HasSubstr(".cc:")));
}

TEST(FrameSourceTest, PreloadGivesTheSameFramesReadBeforehand) {
  TestTempDir dir;
  for (int i = 0; i < 3; ++i) WriteImage(dir.path() / Name(i), Image(64, 32, 40 * i));
  FrameSourceOptions options;
  options.left = dir.path().string();
  const std::unique_ptr<FrameSource> plain = OpenFrameSource(options);
  options.preload = true;
  const std::unique_ptr<FrameSource> preloaded = OpenFrameSource(options);
  EXPECT_EQ(preloaded->size(), 3);
  EXPECT_THAT(preloaded->Describe(), HasSubstr("preloaded"));
  for (int i = 0; i < 3; ++i) {
    const std::optional<SourceFrame> a = plain->Next();
    const std::optional<SourceFrame> b = preloaded->Next();
    ASSERT_TRUE(a && b);
    EXPECT_EQ(b->frame.id, a->frame.id);
    EXPECT_EQ(b->read_s, 0.0);
    EXPECT_EQ(cv::norm(a->frame.left, b->frame.left, cv::NORM_INF), 0.0);
  }
  EXPECT_FALSE(preloaded->Next().has_value());
  FrameSourceOptions camera;
  camera.camera = 0;
  camera.preload = true;
  EXPECT_THROW(camera.Check(), std::invalid_argument);
}

TEST(FrameSourceTest, ACalibrationThatDoesNotFitIsRefusedBeforeTheFirstFrame) {
  TestTempDir dir;
  WriteImage(dir.path() / "l" / "0.png", Image(320, 96, 5));
  WriteImage(dir.path() / "r" / "0.png", Image(320, 96, 5));
  FrameSourceOptions options;
  options.left = (dir.path() / "l").string();
  options.right = (dir.path() / "r").string();
  options.calib = KittiCalib();
  options.needs.right_image = options.needs.calibration = true;
  try {
    OpenFrameSource(options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("does not fit the images"));
    EXPECT_THAT(e.what(), HasSubstr("320x96"));
  }
}

TEST(FrameSourceTest, OptionsNameWhatIsMissingOrTooMuch) {
  FrameSourceOptions none;
  EXPECT_THROW(none.Check(), std::invalid_argument);
  FrameSourceOptions two;
  two.data_root = "d";
  two.left = "l";
  EXPECT_THROW(two.Check(), std::invalid_argument);
  FrameSourceOptions lidar;
  lidar.left = "l";
  lidar.needs.points = true;
  try {
    lidar.Check();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("LiDAR"));
  }
  FrameSourceOptions no_calib;
  no_calib.video = "v.avi";
  no_calib.needs.calibration = true;
  EXPECT_THROW(no_calib.Check(), std::invalid_argument);
  FrameSourceOptions half_video;
  half_video.left_video = "l.avi";
  EXPECT_THROW(half_video.Check(), std::invalid_argument);
}

// A side-by-side stereo video (OpenCV's own MJPEG writer and reader, in every OpenCV build).
TEST(FrameSourceTest, SideBySideVideoGivesBothHalves) {
  TestTempDir dir;
  const fs::path video = dir.path() / "stereo.avi";
  {
    cv::VideoWriter writer(video.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5.0,
                           cv::Size(640, 96));
    if (!writer.isOpened()) GTEST_SKIP() << "this OpenCV writes no MJPEG .avi";
    for (int i = 0; i < 4; ++i) {
      cv::Mat frame(96, 640, CV_8UC3, cv::Scalar(0, 0, 0));
      frame(cv::Rect(320, 0, 320, 96)).setTo(cv::Scalar(200, 200, 200));  // the right half
      writer.write(frame);
    }
  }
  FrameSourceOptions options;
  options.video = video;
  options.needs.right_image = true;
  const std::unique_ptr<FrameSource> source = OpenFrameSource(options);
  EXPECT_EQ(source->fps(), 5.0);
  int n = 0;
  while (std::optional<SourceFrame> f = source->Next()) {
    EXPECT_EQ(f->error, "");
    std::string id = std::to_string(n);
    id.insert(0, 6 - id.size(), '0');
    EXPECT_EQ(f->frame.id, id);
    EXPECT_EQ(f->frame.left.size(), cv::Size(320, 96));
    EXPECT_EQ(f->frame.right.size(), cv::Size(320, 96));
    EXPECT_LT(cv::mean(f->frame.left)[0], 30);    // dark
    EXPECT_GT(cv::mean(f->frame.right)[0], 170);  // bright
    ++n;
  }
  EXPECT_EQ(n, 4);
}

}  // namespace
}  // namespace stereodet
