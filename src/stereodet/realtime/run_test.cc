#include "stereodet/realtime/run.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// A stereo pair of 1242 x 375 px: noise with a bright box, the right image the left shifted 20 px
// (a disparity the matcher finds).
std::pair<cv::Mat, cv::Mat> Pair(cv::RNG& rng, int i) {
  cv::Mat left(375, 1262, CV_8UC3);
  rng.fill(left, cv::RNG::UNIFORM, 40, 120);
  cv::rectangle(left, cv::Rect(320 + 50 * i, 170, 200, 100), cv::Scalar(220, 215, 205), cv::FILLED);
  return {left(cv::Rect(20, 0, 1242, 375)).clone(), left(cv::Rect(0, 0, 1242, 375)).clone()};
}

// Writes `frames` pairs as MJPEG videos: one side by side (`side_by_side`), or left.avi and
// right.avi, the right one `right_short` frames shorter. False when this OpenCV cannot.
bool WriteVideos(const fs::path& dir, int frames, bool side_by_side, int right_short = 0) {
  const int fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  cv::RNG rng(3);
  if (side_by_side) {
    cv::VideoWriter both((dir / "stereo.avi").string(), fourcc, 10.0, cv::Size(2484, 375));
    if (!both.isOpened()) return false;
    for (int i = 0; i < frames; ++i) {
      const auto [left, right] = Pair(rng, i);
      cv::Mat frame;
      cv::hconcat(left, right, frame);
      both.write(frame);
    }
    return true;
  }
  cv::VideoWriter l((dir / "left.avi").string(), fourcc, 10.0, cv::Size(1242, 375));
  cv::VideoWriter r((dir / "right.avi").string(), fourcc, 10.0, cv::Size(1242, 375));
  if (!l.isOpened() || !r.isOpened()) return false;
  for (int i = 0; i < frames; ++i) {
    const auto [left, right] = Pair(rng, i);
    l.write(left);
    if (i < frames - right_short) r.write(right);
  }
  return true;
}

std::vector<std::string> Lines(const fs::path& path) {
  std::istringstream in(ReadFile(path));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

RunOptions RgbhOptions(const fs::path& dir) {
  RunOptions options;
  options.model_dir = TestSourceDir() / "models/ssd-rgbh-learned";
  options.detector.threads = 2;
  options.source.calib = TestSourceDir() / "tests/data/kitti_mini/training/calib/000000.txt";
  options.out = (dir / "frames.jsonl").string();
  options.stream.progress.stream = nullptr;
  return options;
}

TEST(RunTest, SideBySideVideoThroughAnRgbhModel) {
  TestTempDir dir;
  if (!WriteVideos(dir.path(), 3, /*side_by_side=*/true)) GTEST_SKIP() << "no MJPEG writer";
  RunOptions options = RgbhOptions(dir.path());
  options.source.video = dir.path() / "stereo.avi";
  options.kitti_out = dir.path() / "kitti";
  options.summary_json = dir.path() / "summary.json";
  const RunSummary summary = RunDetectorStream(options);
  EXPECT_EQ(summary.family, "ssd");
  EXPECT_EQ(summary.stream.frames_written, 3);
  EXPECT_EQ(summary.stream.frames_failed, 0);
  const std::vector<std::string> lines = Lines(options.out);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[0], HasSubstr(R"("index":0,"id":"000000")"));
  EXPECT_THAT(lines[2], HasSubstr(R"("stereo":)"));  // RGB-H matched the pair
  EXPECT_THAT(lines[2], ::testing::Not(HasSubstr("error")));
  for (const char* file : {"000000.txt", "000001.txt", "000002.txt", "run.json"}) {
    EXPECT_TRUE(fs::exists(options.kitti_out / file)) << file;
  }
  EXPECT_THAT(ReadFile(options.summary_json), HasSubstr(R"("frames_written": 3)"));
  // Run again: its own stream file and KITTI folder are replaced.
  EXPECT_NO_THROW(RunDetectorStream(options));
}

TEST(RunTest, TwoVideosWhoseRightEndsEarlySayItInTheLastLine) {
  TestTempDir dir;
  if (!WriteVideos(dir.path(), 3, /*side_by_side=*/false, /*right_short=*/1)) {
    GTEST_SKIP() << "no MJPEG writer";
  }
  RunOptions options = RgbhOptions(dir.path());
  options.source.left_video = dir.path() / "left.avi";
  options.source.right_video = dir.path() / "right.avi";
  const RunSummary summary = RunDetectorStream(options);
  EXPECT_EQ(summary.stream.frames_failed, 1);
  const std::vector<std::string> lines = Lines(options.out);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_THAT(lines[1], ::testing::Not(HasSubstr("error")));
  EXPECT_THAT(lines[2], HasSubstr("right.avi ended after 2 frames"));
}

TEST(RunTest, RefusesAnOutFileItDidNotWrite) {
  TestTempDir dir;
  RunOptions options = RgbhOptions(dir.path());
  options.source.data_root = TestSourceDir() / "tests/data/kitti_mini";
  options.source.calib.clear();
  WriteFileAtomically(options.out, "{\"precious\": true}\n");
  try {
    RunDetectorStream(options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("is not a stream `run` wrote"));
  }
  EXPECT_EQ(ReadFile(options.out), "{\"precious\": true}\n");
}

}  // namespace
}  // namespace stereodet
