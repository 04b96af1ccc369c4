#include "stereodet/report/eval_report.h"

#include <filesystem>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "stereodet/eval/random_frames.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

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

// With a filter and the optimal matcher: the ROC file is the curve's (FP per frame, recall) in
// ascending FP order, the filtered curves have their own files, and the JSON carries the filtered
// curves' AP and the orientation column where AOS is computed.
TEST(EvalReport, WritesRocAndFilteredCurves) {
  RandomFramesOptions ro;
  ro.num_frames = 20;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.num_threads = 1;
  options.matcher = Matcher::kOptimal;
  options.metrics = {OverlapKind::k2D};
  options.filter.conditions = ParseFilterConditions("min-height=30");
  const EvalResult result = Evaluate(frames, options);
  const TestTempDir dir;
  WriteEvalReport(dir.path(), result, options, EvalRunInfo{});
  const ClassResult& car = *result.Find("Car", OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_FALSE(car.curve.empty());
  const std::string roc = ReadFile(dir.path() / "curves" / "roc_car_2d_moderate.csv");
  std::istringstream lines(roc);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "fp_per_frame,recall,threshold,tp,fp");
  double last_fppf = -1;
  int rows = 0;
  while (std::getline(lines, line)) {
    const double fppf = std::stod(line.substr(0, line.find(',')));
    EXPECT_GE(fppf, last_fppf);
    last_fppf = fppf;
    ++rows;
  }
  EXPECT_EQ(rows, static_cast<int>(car.curve.size()));
  EXPECT_NEAR(last_fppf, static_cast<double>(car.curve.back().fp) / 20, 1e-12);
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "curves" / "pr_naive_car_2d_moderate.csv"));
  const std::string stable = ReadFile(dir.path() / "curves" / "pr_stable_car_2d_moderate.csv");
  EXPECT_EQ(stable.substr(0, stable.find('\n')),
            "threshold,tp,fp,fn,precision,recall,fp_per_frame,orientation");
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir.path() / "results.json"));
  bool found = false;
  for (const auto& r : j["results"]) {
    if (r["class"] == "Car" && r["difficulty"] == "Moderate") {
      EXPECT_DOUBLE_EQ(r["aos_r40"].get<double>(), car.aos_r40);
      EXPECT_DOUBLE_EQ(r["filtered"]["stable_curve"]["ap_r40"].get<double>(), car.filtered->stable_curve.ap_r40);
      EXPECT_EQ(r["filtered"]["naive_curve"]["curve"]["tp"].size(), car.filtered->naive_curve.curve.size());
      EXPECT_EQ(r["curve"]["orientation"].size(), car.curve.size());
      found = true;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_NE(FormatEvalTable(result, options).find("AOS_R40"), std::string::npos);
}

}  // namespace
}  // namespace stereodet
