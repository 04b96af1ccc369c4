#include "stereodet/report/eval_report.h"

#include <filesystem>

#include <gtest/gtest.h>

#include "stereodet/eval/random_frames.h"
#include "stereodet/util/atomic_file.h"

namespace stereodet {
namespace {

TEST(EvalReport, WritesJsonAndCsvThatAgreeWithTheResult) {
  RandomFramesOptions ro;
  ro.num_frames = 30;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.num_threads = 1;
  const EvalResult result = Evaluate(frames, options);
  EvalRunInfo info;
  info.tool_version = "test";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("stereodet_report_test_" + std::to_string(::getpid()));
  const auto written = WriteEvalReport(dir, result, options, info);
  EXPECT_GE(written.size(), 2u);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir / "results.json"));
  EXPECT_EQ(j["options"]["matcher"], "kitti");
  ASSERT_EQ(j["results"].size(), result.results.size());
  const ClassResult& car = *result.Find("Car", OverlapKind::k2D, Difficulty::kModerate);
  bool found = false;
  for (const auto& r : j["results"]) {
    if (r["class"] == "Car" && r["metric"] == "2d" && r["difficulty"] == "Moderate") {
      EXPECT_DOUBLE_EQ(r["ap_r40"].get<double>(), car.ap_r40);
      EXPECT_EQ(r["curve"]["tp"].size(), car.curve.size());
      EXPECT_TRUE(r["ap_voc"].is_null());  // NaN: not computed by the KITTI matcher
      found = true;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_TRUE(std::filesystem::exists(dir / "curves" / "pr_car_2d_moderate.csv"));
  const std::string table = FormatEvalTable(result, options);
  EXPECT_NE(table.find("AP_R40"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace stereodet
