#include "stereodet/util/progress.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// Captures what a reporter writes through a FILE* backed by memory.
class CapturedStream {
 public:
  CapturedStream() : file_(open_memstream(&buffer_, &size_)) {}
  ~CapturedStream() {
    if (file_ != nullptr) std::fclose(file_);
    std::free(buffer_);
  }
  std::FILE* file() { return file_; }
  std::string Text() {
    std::fflush(file_);
    return std::string(buffer_, size_);
  }

 private:
  char* buffer_ = nullptr;
  size_t size_ = 0;
  std::FILE* file_;
};

int CountLines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

TEST(ProgressTest, PlainModePrintsSparseLinesAtPercentSteps) {
  CapturedStream out;
  ProgressOptions options;
  options.stream = out.file();
  options.mode = ProgressOptions::Mode::kPlain;
  {
    ProgressReporter progress("frames", 1000, options);
    for (int i = 0; i < 1000; ++i) progress.Add();
  }
  const std::string text = out.Text();
  // 0%..100% in steps of 10 (0 is not printed: no step reached) plus the final line.
  EXPECT_LE(CountLines(text), 12);
  EXPECT_GE(CountLines(text), 10);
  EXPECT_THAT(text, HasSubstr("frames  1000/1000  100%"));
  EXPECT_THAT(text, HasSubstr(" in "));
  EXPECT_EQ(text.find('\r'), std::string::npos);  // no terminal control codes in logs
}

TEST(ProgressTest, TerminalModeRedrawsOneLine) {
  CapturedStream out;
  ProgressOptions options;
  options.stream = out.file();
  options.mode = ProgressOptions::Mode::kTerminal;
  ProgressReporter progress("train", 0, options);
  progress.Add(5, "loss 0.5");
  progress.Finish();
  progress.Finish();  // idempotent
  const std::string text = out.Text();
  EXPECT_EQ(CountLines(text), 1);
  EXPECT_THAT(text, HasSubstr("\r"));
  EXPECT_THAT(text, HasSubstr("loss 0.5"));
  EXPECT_EQ(progress.done(), 5);
}

TEST(ProgressTest, CountsCorrectlyFromManyThreads) {
  ProgressOptions options;
  options.stream = nullptr;
  ProgressReporter progress("x", 10000, options);
  ParallelFor(
      10000, [&](size_t) { progress.Add(); }, 2);
  EXPECT_EQ(progress.done(), 10000);
}

TEST(StageTimesTest, AccumulatesPerStageInFirstSeenOrder) {
  StageTimes times;
  times.Add("disparity", 0.5);
  times.Add("encode", 0.25);
  times.Add("disparity", 1.5);
  const auto snapshot = times.Snapshot();
  EXPECT_DOUBLE_EQ(snapshot.at("disparity").total_s, 2.0);
  EXPECT_EQ(snapshot.at("disparity").count, 2);
  const std::string text = times.Format();
  EXPECT_LT(text.find("disparity"), text.find("encode"));
  EXPECT_THAT(text, HasSubstr("1000.00 ms/call"));
}

}  // namespace
}  // namespace stereodet
