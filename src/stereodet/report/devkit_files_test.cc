#include "stereodet/report/devkit_files.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "stereodet/pipelines/evaluation.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kSmall = ::stereodet::TestSourceDir() / "tests/data/eval_small";

EvaluationOptions SmallWithDevkitFiles(const fs::path& out) {
  EvaluationOptions options;
  options.input.gt = kSmall;
  options.input.det = kSmall / "det";
  options.out = out;
  options.devkit_files = true;
  return options;
}

// tests/data/eval_small/devkit holds what KITTI's official devkit wrote on these frames (its
// README): every stats file is those bytes, and the run writes no other stats file.
TEST(DevkitFilesTest, StatsFilesAreTheOfficialDevkitsBytes) {
  TestTempDir dir;
  const EvaluationResult result = RunEvaluation(SmallWithDevkitFiles(dir / "eval"));
  int compared = 0;
  for (const auto& e : fs::directory_iterator(kSmall / "devkit")) {
    const fs::path ours = dir / "eval" / e.path().filename();
    ASSERT_TRUE(fs::exists(ours)) << ours;
    EXPECT_EQ(ReadFile(ours), ReadFile(e.path())) << e.path().filename();
    ++compared;
  }
  EXPECT_EQ(compared, 12);
  int stats = 0;
  for (const auto& e : fs::directory_iterator(dir / "eval")) {
    stats += e.path().filename().string().rfind("stats_", 0) == 0;
  }
  EXPECT_EQ(stats, 12);
  EXPECT_EQ(std::count(result.files.begin(), result.files.end(),
                       dir / "eval" / "stats_car_detection.txt"),
            1);
}

// plot/CLASS_KIND.txt: 41 lines "%f %f %f %f" of recall i/40 and the stats file's three lines'
// slot i (the data the devkit's gnuplot script reads).
TEST(DevkitFilesTest, PlotFilesHoldRecallAndTheThreeDifficultiesSlots) {
  TestTempDir dir;
  RunEvaluation(SmallWithDevkitFiles(dir / "eval"));
  for (const char* kind : {"detection", "orientation", "detection_ground", "detection_3d"}) {
    const std::string stats = ReadFile(dir / "eval" / (std::string("stats_car_") + kind + ".txt"));
    std::vector<std::vector<std::string>> slots;  // [difficulty][slot]
    for (std::string_view line : Split(stats, '\n')) {
      if (line.empty()) continue;
      slots.emplace_back();
      for (std::string_view token : SplitWhitespace(line)) slots.back().emplace_back(token);
    }
    ASSERT_EQ(slots.size(), 3u) << kind;
    const std::string plot =
        ReadFile(dir / "eval" / "plot" / (std::string("car_") + kind + ".txt"));
    std::istringstream lines(plot);
    std::string line;
    for (int i = 0; i < 41; ++i) {
      ASSERT_TRUE(std::getline(lines, line)) << kind << " line " << i;
      char recall[64];
      std::snprintf(recall, sizeof(recall), "%f", i / 40.0);
      EXPECT_EQ(line,
                std::string(recall) + " " + slots[0][i] + " " + slots[1][i] + " " + slots[2][i])
          << kind << " line " << i;
    }
    EXPECT_FALSE(std::getline(lines, line)) << kind;
    EXPECT_EQ(plot.back(), '\n');
  }
}

// RunEvaluation's std::invalid_argument message, or "" when it did not throw one.
std::string RefusalOf(const EvaluationOptions& options) {
  try {
    RunEvaluation(options);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(DevkitFilesTest, RefusedWithoutTheKittiMatcherOrAllThreeDifficulties) {
  TestTempDir dir;
  EvaluationOptions optimal = SmallWithDevkitFiles(dir / "optimal");
  optimal.runs.front().matcher = Matcher::kOptimal;
  EXPECT_THAT(RefusalOf(optimal), HasSubstr("only the KITTI matcher computes"));
  EXPECT_FALSE(fs::exists(dir / "optimal"));
  EvaluationOptions moderate = SmallWithDevkitFiles(dir / "moderate");
  moderate.runs.front().difficulties = {Difficulty::kModerate};
  EXPECT_THAT(RefusalOf(moderate), HasSubstr("at Easy, Moderate and Hard"));
  EXPECT_FALSE(fs::exists(dir / "moderate" / "results.json"));  // nothing committed
  EXPECT_THAT(RefusalOf(SmallWithDevkitFiles("")), HasSubstr("needs an output folder"));
}

}  // namespace
}  // namespace stereodet
