#include "stereodet/report/eval_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>

#include "stereodet/eval/random_frames.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

TEST(EvalReportTest, WritesJsonAndCsvThatAgreeWithTheResult) {
  RandomFramesOptions ro;
  ro.num_frames = 30;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.num_threads = 1;
  const EvalResult result = Evaluate(frames, options);
  EvalRunInfo info;
  info.tool_version = "test";
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("stereodet_report_test_" + std::to_string(::getpid()));
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
      // The curve is in the CSV results.json names (one row per point), not in results.json.
      EXPECT_FALSE(r.contains("curve"));
      EXPECT_EQ(r["curve_csv"], "curves/pr_car_2d_moderate.csv");
      EXPECT_EQ(r["roc_csv"], "curves/roc_car_2d_moderate.csv");
      EXPECT_EQ(r["curve_points"], car.curve.size());
      const std::string csv = ReadFile(dir / r["curve_csv"].get<std::string>());
      EXPECT_EQ(csv, PrCsv(car.curve, result.num_frames, car.has_aos));
      EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), car.curve.size() + 1);
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

// The curve CSVs of a hand-made two-point curve, byte for byte: shortest round-trip numbers,
// integers as integers, NaN as an empty field.
TEST(EvalReportTest, CurveCsvTextByHand) {
  CurvePoint a;
  a.threshold = 0.9;
  a.tp = 1;
  a.fp = 0;
  a.fn = 2;
  a.precision = 1.0;
  a.recall = 1.0 / 3.0;
  a.orientation = 0.5;
  CurvePoint b;
  b.threshold = 0.25;
  b.tp = 2;
  b.fp = 1;
  b.fn = 1;
  b.precision = 2.0 / 3.0;
  b.recall = 2.0 / 3.0;
  b.orientation = std::nan("");
  EXPECT_EQ(PrCsv({a, b}, 4, true),
            "threshold,tp,fp,fn,precision,recall,fp_per_frame,orientation\n"
            "0.9,1,0,2,1,0.3333333333333333,0,0.5\n"
            "0.25,2,1,1,0.6666666666666666,0.6666666666666666,0.25,\n");
  EXPECT_EQ(PrCsv({a}, 0, false),
            "threshold,tp,fp,fn,precision,recall,fp_per_frame\n0.9,1,0,2,1,0.3333333333333333,0\n");
  EXPECT_EQ(RocCsv({a, b}, 4),
            "fp_per_frame,recall,threshold,tp,fp\n"
            "0,0.3333333333333333,0.9,1,0\n"
            "0.25,0.6666666666666666,0.25,2,1\n");
}

// With a filter and the optimal matcher: the ROC file is the curve's (FP per frame, recall) in
// ascending FP order, the filtered curves have their own files, and the JSON carries the filtered
// curves' AP and the orientation column where AOS is computed.
TEST(EvalReportTest, WritesRocAndFilteredCurves) {
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
      EXPECT_DOUBLE_EQ(r["filtered"]["stable_curve"]["ap_r40"].get<double>(),
                       car.filtered->stable_curve.ap_r40);
      EXPECT_EQ(r["filtered"]["naive_curve"]["curve_points"],
                car.filtered->naive_curve.curve.size());
      EXPECT_EQ(r["filtered"]["naive_curve"]["curve_csv"],
                "curves/pr_naive_" + r["curve_csv"].get<std::string>().substr(10));
      EXPECT_EQ(
          ReadFile(dir.path() / r["filtered"]["stable_curve"]["curve_csv"].get<std::string>()),
          PrCsv(car.filtered->stable_curve.curve, 20, true));
      EXPECT_EQ(ReadFile(dir.path() / r["curve_csv"].get<std::string>()),
                PrCsv(car.curve, 20, true));  // with its orientation column
      found = true;
    }
  }
  EXPECT_TRUE(found);
  EXPECT_NE(FormatEvalTable(result, options).find("AOS_R40"), std::string::npos);
}

// --overlaps strict,loose: one block per set in the table, results tagged in results.json and in
// summary.csv, curve files suffixed; the input record (ignored files, skipped lines) and the notes
// (small samples) are written.
TEST(EvalReportTest, SeveralOverlapSetsAreTaggedAndNotesAreWritten) {
  RandomFramesOptions ro;
  ro.num_frames = 8;  // few labels per cell: small samples
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  std::vector<EvalRun> runs;
  for (const bool loose : {false, true}) {
    EvalOptions options;
    options.num_threads = 1;
    options.classes = {KittiClassSpec("Car", loose)};
    options.metrics = {OverlapKind::kBev};
    runs.push_back(EvalRun{options, Evaluate(frames, options)});
  }
  EvalRunInfo info;
  info.lenient = true;
  info.skipped_lines = {"det/000001.txt:2: field score: 'abc' is not a number"};
  info.ignored_files = {"det/009999.txt"};
  const TestTempDir dir;
  WriteEvalReport(dir.path(), runs, info);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(dir.path() / "results.json"));
  EXPECT_EQ(j["options"]["overlaps"], nlohmann::json::array({"strict", "loose"}));
  EXPECT_EQ(j["overlap_sets"][1]["classes"][0]["min_overlap"][1], 0.5);
  ASSERT_EQ(j["results"].size(), runs[0].result.results.size() + runs[1].result.results.size());
  EXPECT_EQ(j["results"].front()["overlaps"], "strict");
  EXPECT_EQ(j["results"].back()["overlaps"], "loose");
  EXPECT_EQ(j["results"].back()["min_overlap"], 0.5);
  EXPECT_EQ(j["input"]["num_skipped_lines"], 1);
  EXPECT_EQ(j["input"]["skipped_lines"][0], info.skipped_lines[0]);
  EXPECT_EQ(j["input"]["ignored_files"][0], "det/009999.txt");
  EXPECT_TRUE(j["scores"]["probability_metrics"].get<bool>());
  const ClassResult& car = *runs[0].result.Find("Car", OverlapKind::kBev, Difficulty::kModerate);
  ASSERT_TRUE(IsSmallSample(car));
  EXPECT_TRUE(j["results"][1]["small_sample"].get<bool>());
  EXPECT_NE(j["notes"].dump().find("40 or fewer valid labels"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "curves" / "pr_car_bev_moderate_strict.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "curves" / "pr_car_bev_moderate_loose.csv"));
  // Every evaluated cell names its own run's curve files, which are there.
  for (const auto& r : j["results"]) {
    if (!r["evaluated"].get<bool>()) continue;
    const std::string file = r["curve_csv"].get<std::string>();
    const std::string tail = "_" + r["overlaps"].get<std::string>() + ".csv";
    ASSERT_GE(file.size(), tail.size());
    EXPECT_EQ(file.substr(file.size() - tail.size()), tail);
    EXPECT_TRUE(std::filesystem::exists(dir.path() / file)) << file;
    EXPECT_TRUE(std::filesystem::exists(dir.path() / r["roc_csv"].get<std::string>()));
  }
  const std::string summary = ReadFile(dir.path() / "summary.csv");
  EXPECT_NE(summary.find(",loose\n"), std::string::npos);
  EXPECT_NE(summary.find(",strict\n"), std::string::npos);

  const std::string table = FormatEvalTable(runs);
  const size_t strict = table.find("overlaps strict"), loose = table.find("overlaps loose");
  ASSERT_NE(strict, std::string::npos);
  ASSERT_NE(loose, std::string::npos);
  EXPECT_LT(strict, loose);
  EXPECT_NE(table.find("Car          bev   0.50 | AP_R40"), std::string::npos);
  EXPECT_NE(table.find(std::to_string(car.num_valid_labels) + "*"), std::string::npos);
  EXPECT_NE(table.find("Brier_L"), std::string::npos);
  EXPECT_NE(table.find("ECE"), std::string::npos);
}

// Scores that are not probabilities: the table and results.json say so, and Brier / ECE are null.
TEST(EvalReportTest, ScoresOutsideTheUnitIntervalAreReported) {
  RandomFramesOptions ro;
  ro.num_frames = 5;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  for (EvalFrame& f : frames) {
    for (Object& d : f.detections) d.score = *d.score * 10 - 5;  // logit-like
  }
  EvalOptions options;
  options.num_threads = 1;
  options.metrics = {OverlapKind::k2D};
  const EvalResult result = Evaluate(frames, options);
  // NaN is a number in memory and null once written.
  const nlohmann::json j =
      nlohmann::json::parse(EvalResultToJson(result, options, EvalRunInfo{}).dump());
  EXPECT_FALSE(j["scores"]["probability_metrics"].get<bool>());
  for (const auto& r : j["results"]) {
    if (!r["evaluated"].get<bool>()) continue;
    EXPECT_TRUE(r["brier"]["over_labels"].is_null());
    EXPECT_TRUE(r["calibration"]["ece"].is_null());
  }
  EXPECT_NE(j["notes"].dump().find("--score-transform sigmoid"), std::string::npos);
  EXPECT_NE(FormatEvalTable(result, options).find("Brier and ECE are left out"), std::string::npos);
}

}  // namespace
}  // namespace stereodet
