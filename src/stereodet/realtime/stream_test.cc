#include "stereodet/realtime/stream.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "stereodet/kitti/label_io.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Six frames of 1242 x 375 px: textured noise with a bright box, a little different each time.
void WriteSequence(const fs::path& dir, int frames) {
  fs::create_directories(dir);
  cv::RNG rng(11);
  for (int i = 0; i < frames; ++i) {
    cv::Mat image(375, 1242, CV_8UC3);
    rng.fill(image, cv::RNG::UNIFORM, 40, 90);
    cv::rectangle(image, cv::Rect(300 + 60 * i, 170, 180, 90), cv::Scalar(220, 210, 200),
                  cv::FILLED);
    ASSERT_TRUE(cv::imwrite((dir / ("f" + std::to_string(i) + ".png")).string(), image));
  }
}

Detector OpenRgbModel() {
  DetectorOptions options;
  options.threads = 2;
  return Detector::Open(TestSourceDir() / "models/ssd-rgb", options);
}

std::unique_ptr<FrameSource> Sequence(const fs::path& dir, double fps = 0) {
  FrameSourceOptions options;
  options.left = dir.string();
  options.fps = fps;
  return OpenFrameSource(options);
}

TEST(StreamTest, EveryFrameInOrderWithTheObjectsOfDetect) {
  TestTempDir dir;
  WriteSequence(dir.path(), 6);
  Detector detector = OpenRgbModel();
  std::unique_ptr<FrameSource> source = Sequence(dir.path());
  StreamOptions options;
  options.warmup_frames = 2;
  options.progress.stream = nullptr;
  std::vector<StreamFrame> got;
  const StreamSummary summary =
      RunStream(detector, *source, options, [&](const StreamFrame& f) { got.push_back(f); });
  ASSERT_EQ(got.size(), 6u);
  EXPECT_EQ(summary.frames_read, 6);
  EXPECT_EQ(summary.frames_written, 6);
  EXPECT_EQ(summary.frames_failed, 0);
  EXPECT_EQ(summary.frames_dropped, 0);
  EXPECT_FALSE(summary.interrupted);
  EXPECT_EQ(summary.latency.Summary("network").frames, 4);  // after the 2 warm-up frames
  EXPECT_EQ(summary.latency.Summary("network", true).frames, 2);
  // The same objects as one Detect call per frame, read afresh.
  std::unique_ptr<FrameSource> again = Sequence(dir.path());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].source.index, static_cast<int64_t>(i));
    EXPECT_EQ(got[i].error(), "");
    EXPECT_TRUE(got[i].source.frame.left.empty());  // released after detection
    const std::optional<SourceFrame> frame = again->Next();
    ASSERT_TRUE(frame.has_value());
    const DetectResult direct = detector.Detect(frame->frame);
    EXPECT_EQ(FormatObjects(got[i].result.objects), FormatObjects(direct.objects)) << "frame " << i;
    for (const char* stage : {"read", "encode", "network", "decode", "wait", "end_to_end"}) {
      ASSERT_TRUE(got[i].latency_ms.count(stage)) << stage;
      EXPECT_GE(got[i].latency_ms.at(stage), 0.0) << stage;
    }
    EXPECT_GE(got[i].latency_ms.at("end_to_end"), got[i].latency_ms.at("network"));
  }
  EXPECT_GT(got[0].result.objects.size(), 0u);  // not vacuous
}

TEST(StreamTest, StopFinishesTheFramesInFlightAndSaysItWasInterrupted) {
  TestTempDir dir;
  WriteSequence(dir.path(), 12);
  Detector detector = OpenRgbModel();
  std::unique_ptr<FrameSource> source = Sequence(dir.path());
  StreamOptions options;
  options.queue_capacity = 1;  // at most 6 frames in flight: the reader's, 3 queued, 2 in stages
  options.progress.stream = nullptr;
  std::atomic<bool> stop{false};
  std::vector<int64_t> indices;
  const StreamSummary summary = RunStream(
      detector, *source, options,
      [&](const StreamFrame& f) {
        indices.push_back(f.source.index);
        stop = true;  // Ctrl-C after the first frame
      },
      &stop);
  EXPECT_TRUE(summary.interrupted);
  ASSERT_GE(indices.size(), 1u);
  EXPECT_LT(indices.size(), 12u);
  // Every frame read was written, in order: nothing in flight is lost.
  EXPECT_EQ(summary.frames_written, summary.frames_read);
  for (size_t i = 0; i < indices.size(); ++i) EXPECT_EQ(indices[i], static_cast<int64_t>(i));
}

TEST(StreamTest, RealtimeDropsOnlyWhatALaterFrameReplacesAndKeepsTheLast) {
  TestTempDir dir;
  WriteSequence(dir.path(), 6);
  Detector detector = OpenRgbModel();
  // 1000 frames/s: far faster than the detector, so the reader replaces frames still waiting.
  std::unique_ptr<FrameSource> source = Sequence(dir.path(), 1000.0);
  StreamOptions options;
  options.realtime = true;
  options.progress.stream = nullptr;
  std::vector<int64_t> indices;
  const StreamSummary summary = RunStream(
      detector, *source, options, [&](const StreamFrame& f) { indices.push_back(f.source.index); });
  EXPECT_EQ(summary.frames_read, 6);
  EXPECT_EQ(summary.frames_written + summary.frames_dropped, summary.frames_read);
  ASSERT_FALSE(indices.empty());
  EXPECT_EQ(indices.back(), 5);  // the latest frame wins: the last is never dropped
  for (size_t i = 1; i < indices.size(); ++i) EXPECT_LT(indices[i - 1], indices[i]);
}

TEST(StreamTest, ABrokenFrameIsReportedOrWithStrictStopsTheStream) {
  TestTempDir dir;
  WriteSequence(dir.path(), 3);
  std::ofstream(dir.path() / "f1.png", std::ios::trunc) << "not a png";
  Detector detector = OpenRgbModel();
  StreamOptions options;
  options.progress.stream = nullptr;
  std::vector<std::string> errors;
  std::unique_ptr<FrameSource> source = Sequence(dir.path());
  const StreamSummary summary = RunStream(
      detector, *source, options, [&](const StreamFrame& f) { errors.push_back(f.error()); });
  ASSERT_EQ(errors.size(), 3u);
  EXPECT_EQ(errors[0], "");
  EXPECT_THAT(errors[1], HasSubstr("f1.png"));
  EXPECT_EQ(errors[2], "");
  EXPECT_EQ(summary.frames_failed, 1);

  options.strict = true;
  source = Sequence(dir.path());
  try {
    RunStream(detector, *source, options, [](const StreamFrame&) {});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("frame 1 (f1)"));
    EXPECT_THAT(e.what(), HasSubstr("--strict"));
  }
}

TEST(StreamTest, FrameJsonByHand) {
  StreamFrame frame;
  frame.source.index = 3;
  frame.source.frame.id = "000003";
  frame.source.frame.timestamp_s = 0.3;
  Object car;
  car.type = "Car";
  car.score = 0.9123456789;
  car.box = {10.004, 20, 30.5, 40.126};
  car.box3d.h = 1.5;
  car.box3d.w = 1.6;
  car.box3d.l = 3.9;
  car.box3d.location = {1.0, 1.7, 20.004};
  car.box3d.rotation_y = 0.1;
  car.alpha = -0.05;
  Object person;
  person.type = "Pedestrian";
  person.score = 0.5;
  person.box = {1, 2, 3, 4};
  person.SetNot3DEstimated();
  frame.result.objects = {car, person};
  frame.latency_ms = {{"network", 12.34567}, {"end_to_end", 20.0}, {"unknown", 1.0}};
  EXPECT_EQ(StreamFrameJson(frame),
            R"({"index":3,"id":"000003","timestamp_s":0.3,"objects":[)"
            R"({"type":"Car","score":0.912346,"box_2d":[10.0,20.0,30.5,40.13],)"
            R"("dimensions_m":[1.5,1.6,3.9],"location_m":[1.0,1.7,20.0],"rotation_y":0.1,)"
            R"("alpha":-0.05},{"type":"Pedestrian","score":0.5,"box_2d":[1.0,2.0,3.0,4.0]}],)"
            R"("latency_ms":{"network":12.346,"end_to_end":20.0}})");
  frame.source.error = "cannot read image x.png";
  frame.result.objects.clear();
  EXPECT_THAT(StreamFrameJson(frame), HasSubstr(R"("objects":[],)"));
  EXPECT_THAT(StreamFrameJson(frame), HasSubstr(R"(,"error":"cannot read image x.png"})"));
}

}  // namespace
}  // namespace stereodet
