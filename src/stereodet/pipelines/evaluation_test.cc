#include "stereodet/pipelines/evaluation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/eval/openpcdet_compat.h"
#include "stereodet/geometry/calibration.h"
#include "stereodet/report/bootstrap_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const fs::path kData = ::stereodet::TestSourceDir() / "tests/data";

// tests/data/eval_small (README): KITTI's devkit gives Car 2D AP_R40 6.25 / 15.77 / 15.77.
// A CSV line's fields (no quoting: breakdown.csv has none).
std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> fields;
  for (std::string_view f : Split(line, ',')) fields.emplace_back(f);
  return fields;
}

EvaluationOptions SmallCar2d() {
  EvaluationOptions options;
  options.input.gt = kData / "eval_small";
  options.input.det = kData / "eval_small/det";
  options.runs.front().classes = {KittiClassSpec("Car")};
  options.runs.front().metrics = {OverlapKind::k2D};
  return options;
}

int64_t CountLines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

TEST(OverlapSetRunsTest, OneRunPerSetWithThatSetsThresholdsAndTheRestKept) {
  EvalOptions base;
  base.classes = {KittiClassSpec("Car"), KittiClassSpec("Pedestrian")};
  base.classes[0].min_overlap = {0.9, 0.9, 0.9};  // custom: replaced
  base.matcher = Matcher::kOptimal;
  base.score_threshold = 0.3;
  const std::vector<EvalOptions> runs =
      OverlapSetRuns(base, {OverlapSet::kLoose, OverlapSet::kStrict});
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(DescribeOverlaps(runs[0].classes), "loose");
  EXPECT_EQ(DescribeOverlaps(runs[1].classes), "strict");
  EXPECT_EQ(runs[0].classes[0].min_overlap, KittiClassSpec("Car", true).min_overlap);
  EXPECT_EQ(runs[1].classes[0].min_overlap, (std::array<double, 5>{0.7, 0.7, 0.7, 0.7, 0.7}));
  EXPECT_EQ(runs[1].classes[1].name, "Pedestrian");
  for (const EvalOptions& run : runs) {
    EXPECT_EQ(run.matcher, Matcher::kOptimal);
    EXPECT_EQ(run.score_threshold, 0.3);
  }

  base.matcher = Matcher::kKitti;
  base.compat = EvalCompat::kOpenPcdet;
  const std::vector<EvalOptions> openpcdet = OverlapSetRuns(base, {OverlapSet::kLoose});
  EXPECT_EQ(openpcdet[0].classes[0].min_overlap, OpenPcdetClassSpec("Car", true).min_overlap);
  EXPECT_TRUE(OverlapSetRuns(base, {}).empty());
}

TEST(EvaluationOptionsTest, Check) {
  EXPECT_NO_THROW(SmallCar2d().Check());
  EvaluationOptions no_gt = SmallCar2d();
  no_gt.input.gt.clear();
  EXPECT_THROW(no_gt.Check(), std::invalid_argument);
  EvaluationOptions no_runs = SmallCar2d();
  no_runs.runs.clear();
  EXPECT_THROW(no_runs.Check(), std::invalid_argument);
  EvaluationOptions records = SmallCar2d();
  records.records = true;
  EXPECT_THROW(records.Check(), std::invalid_argument);  // records without out
  EvaluationOptions compat = SmallCar2d();
  compat.runs.push_back(compat.runs.front());
  compat.runs.back().compat = EvalCompat::kOpenPcdet;
  EXPECT_THROW(compat.Check(), std::invalid_argument);
  EvaluationOptions bad_run = SmallCar2d();
  bad_run.runs.front().calibration_bins = 0;
  EXPECT_THROW(bad_run.Check(), std::invalid_argument);
}

TEST(RunEvaluationTest, GivesTheDevkitNumbersAndWhatTheSeparateCallsGive) {
  const EvaluationOptions options = SmallCar2d();
  const EvaluationResult result = RunEvaluation(options);
  ASSERT_EQ(result.runs.size(), 1u);
  const EvalResult& r = result.runs[0].result;
  const ClassResult* easy = r.Find("Car", OverlapKind::k2D, Difficulty::kEasy);
  const ClassResult* moderate = r.Find("Car", OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_NE(easy, nullptr);
  ASSERT_NE(moderate, nullptr);
  EXPECT_NEAR(easy->ap_r40, 6.25, 0.005);
  EXPECT_NEAR(moderate->ap_r40, 15.77, 0.005);
  EXPECT_EQ(result.seconds, r.seconds);
  EXPECT_TRUE(result.files.empty());  // no out
  EXPECT_TRUE(result.records.empty());

  // The same as LoadEvalFrames + Evaluate + the table.
  const EvalInput input = LoadEvalFrames(options.input);
  EXPECT_EQ(result.input.frames.size(), input.frames.size());
  EXPECT_EQ(result.input.input_hash, input.input_hash);
  const EvalResult direct = Evaluate(input.frames, options.runs[0]);
  EXPECT_EQ(FormatEvalTable(result.runs), FormatEvalTable({EvalRun{options.runs[0], direct}}));

  // What results.json records about the input.
  EXPECT_EQ(result.info.gt_path, options.input.gt.string());
  EXPECT_EQ(result.info.det_path, options.input.det.string());
  EXPECT_EQ(result.info.input_hash, input.input_hash);
}

TEST(RunEvaluationTest, WritesOneResultsFolderWithRecordsPerOverlapSet) {
  TestTempDir dir;
  EvaluationOptions options = SmallCar2d();
  options.runs = OverlapSetRuns(options.runs.front(), {OverlapSet::kStrict, OverlapSet::kLoose});
  options.out = dir / "eval";
  options.records = true;
  options.tool_version = "test-version";
  options.command_line = "stereodet eval ...";
  const EvaluationResult result = RunEvaluation(options);

  ASSERT_EQ(result.records.size(), 2u);
  EXPECT_EQ(result.records[0].name, "matches_strict.csv");
  EXPECT_EQ(result.records[1].name, "matches_loose.csv");
  for (const EvaluationResult::RecordsFile& records : result.records) {
    EXPECT_GT(records.rows, 0);
    EXPECT_EQ(CountLines(ReadFile(options.out / records.name)), records.rows + 1) << records.name;
  }
  for (const EvalRun& run : result.runs) EXPECT_TRUE(run.options.keep_records);
  // Every file listed is there, under out, and nothing else is.
  std::vector<fs::path> listed = result.files, found;
  for (const auto& entry : fs::recursive_directory_iterator(options.out)) {
    if (entry.is_regular_file()) found.push_back(entry.path());
  }
  std::sort(listed.begin(), listed.end());
  std::sort(found.begin(), found.end());
  EXPECT_EQ(listed, found);
  EXPECT_NE(std::find(listed.begin(), listed.end(), options.out / "results.json"), listed.end());
  // Only the folder itself beside it: no staging folder left.
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 1);

  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["command_line"], "stereodet eval ...");
  EXPECT_EQ(j["input_hash"], result.info.input_hash);
  EXPECT_THAT(j.dump(), HasSubstr("test-version"));

  // A second run replaces the folder whole: one records file now.
  options.runs.resize(1);
  const EvaluationResult again = RunEvaluation(options);
  EXPECT_EQ(again.records.size(), 1u);
  EXPECT_TRUE(fs::exists(options.out / "matches.csv"));
  EXPECT_FALSE(fs::exists(options.out / "matches_loose.csv"));
}

TEST(RunEvaluationTest, RefusesAFolderOfOtherFilesBeforeReadingAnything) {
  TestTempDir dir;
  WriteFileAtomically(dir / "mine/notes.txt", "keep me\n");
  EvaluationOptions options = SmallCar2d();
  options.input.gt = dir / "no_such_labels";  // reading it would fail with another message
  options.out = dir / "mine";
  try {
    RunEvaluation(options);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("mine is a folder of other files (notes.txt); eval replaces "
                                    "or writes into only a folder that eval made"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("no_such_labels")));
  }
  EXPECT_EQ(ReadFile(dir / "mine/notes.txt"), "keep me\n");
}

TEST(RunEvaluationSweepTest, IsFilterSweepOnTheFramesAndWritesItsCsv) {
  TestTempDir dir;
  EvaluationSweepOptions options;
  options.input = SmallCar2d().input;
  options.eval = SmallCar2d().runs.front();
  options.bound = FilterBound::kMinArea;
  options.from = 0;
  options.to = 200;
  options.step = 50;
  options.out = dir / "sweep";
  const EvaluationSweepResult result = RunEvaluationSweep(options);
  const std::vector<SweepRow> direct =
      FilterSweep(LoadEvalFrames(options.input).frames, options.eval, options.bound, 0, 200, 50);
  EXPECT_EQ(result.csv, FormatSweepCsv(direct, options.bound));
  EXPECT_EQ(result.rows.size(), direct.size());
  // 5 values (0, 50, ..., 200) for each of Car 2D x 3 difficulties, and a header.
  EXPECT_EQ(CountLines(result.csv), 1 + 5 * 3);
  EXPECT_EQ(result.csv_path, options.out / "sweep.csv");
  EXPECT_EQ(ReadFile(result.csv_path), result.csv);
  options.out.clear();
  EXPECT_TRUE(RunEvaluationSweep(options).csv_path.empty());
}

// tests/data/eval_compare (README): per 5 m bin, mean |dz| A 0.500 / B 0.200 (10-15 m) and
// 1.000 / 2.000 (20-25 m).
TEST(RunEvaluationCompareTest, GivesTheKnownDepthErrorsPerBin) {
  TestTempDir dir;
  EvaluationCompareOptions options;
  options.input.gt = kData / "eval_compare";
  options.input.det = kData / "eval_compare/det_a";
  options.det_b = kData / "eval_compare/det_b";
  options.eval.classes = {KittiClassSpec("Car")};
  options.eval.metrics = {OverlapKind::k2D};
  options.eval.difficulties = {Difficulty::kModerate};
  options.out = dir / "compare";
  const EvaluationCompareResult result = RunEvaluationCompare(options);
  EXPECT_EQ(result.compare.baseline_m, KittiLikeCalibration().BaselineM());
  EXPECT_EQ(result.compare.focal_px, KittiLikeCalibration().FocalPx());
  EXPECT_EQ(result.compare.disparity_error_px, 1.0);
  int checked = 0;
  for (const CompareRow& row : result.rows) {
    if (row.lower_m == 10) {
      EXPECT_EQ(row.count_a, 1);
      EXPECT_NEAR(row.abs_depth_error_mean_a_m, 0.5, 1e-9);
      EXPECT_NEAR(row.abs_depth_error_mean_b_m, 0.2, 1e-9);
      ++checked;
    } else if (row.lower_m == 20) {
      EXPECT_NEAR(row.abs_depth_error_mean_a_m, 1.0, 1e-9);
      EXPECT_NEAR(row.abs_depth_error_mean_b_m, 2.0, 1e-9);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2);
  const std::string table = FormatCompareTable(result.rows);
  EXPECT_THAT(table, HasSubstr("\nCar 2d Moderate: mean |depth error| of matched pairs (m)\n"));
  EXPECT_THAT(table, ::testing::ContainsRegex("10-15 +m +1 +0.500 +1 +0.200 +-0.300"));
  EXPECT_EQ(ReadFile(result.csv_path), result.csv);
  EXPECT_EQ(result.csv, FormatCompareCsv(result.rows));

  EvaluationCompareOptions no_b = options;
  no_b.det_b.clear();
  EXPECT_THROW(RunEvaluationCompare(no_b), std::invalid_argument);
}

// --bootstrap: results.json carries the settings and each cell's intervals, whose estimates are the
// cell's own numbers; the table has the block; the same seed gives the same file.
TEST(RunEvaluationTest, BootstrapIntervalsInResultsJsonAndTheTable) {
  TestTempDir dir;
  EvaluationOptions options = SmallCar2d();
  options.out = dir / "eval";
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 60;
  bootstrap.seed = 5;
  options.bootstrap = bootstrap;
  const EvaluationResult result = RunEvaluation(options);
  ASSERT_EQ(result.runs.size(), 1u);
  ASSERT_TRUE(result.runs[0].bootstrap.has_value());
  EXPECT_EQ(result.runs[0].bootstrap->num_resamples, 60);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["bootstrap"]["resamples"], 60);
  EXPECT_EQ(j["bootstrap"]["seed"], 5);
  EXPECT_EQ(j["bootstrap"]["confidence"], 0.95);
  int checked = 0;
  for (const nlohmann::json& cell : j["results"]) {
    ASSERT_TRUE(cell.contains("bootstrap")) << cell.dump();
    const nlohmann::json& ap = cell["bootstrap"]["ap_r40"];
    EXPECT_EQ(ap["estimate"], cell["ap_r40"]);
    EXPECT_LE(ap["lower"].get<double>(), ap["upper"].get<double>());
    EXPECT_EQ(ap["resamples_defined"], 60);
    EXPECT_FALSE(cell["bootstrap"].contains("ap_voc"));  // the KITTI matcher has none
    EXPECT_TRUE(cell["bootstrap"].contains("brier_labels"));
    ++checked;
  }
  EXPECT_EQ(checked, 3);
  const std::string table = FormatEvalTable(result.runs);
  EXPECT_THAT(table, HasSubstr("bootstrap: 60 resamples of the 12 frames (seed 5), 95% "
                               "percentile intervals\n"));
  EXPECT_THAT(table, ::testing::ContainsRegex("Car +2d +Moderate +[|] 15.77 [[][0-9.]+, [0-9.]+[]] "
                                              "+22.00 [[]"));
  // Without --bootstrap: no key, no block.
  options.bootstrap.reset();
  const EvaluationResult plain = RunEvaluation(options);
  EXPECT_FALSE(nlohmann::json::parse(ReadFile(options.out / "results.json")).contains("bootstrap"));
  EXPECT_THAT(FormatEvalTable(plain.runs), ::testing::Not(HasSubstr("bootstrap:")));
  options.bootstrap = bootstrap;
  options.bootstrap->confidence = 1.5;
  EXPECT_THROW(RunEvaluation(options), std::invalid_argument);
}

// --errors: each evaluated cell's "errors" in results.json is AnalyzeAllErrors' analysis of the
// cell, errors.csv has its eight rows (six types, FP, FN) with the same numbers, the table its
// block and the report its figure; refused with --compat openpcdet.
TEST(RunEvaluationTest, ErrorAnalysisInResultsJsonErrorsCsvTheTableAndTheReport) {
  TestTempDir dir;
  EvaluationOptions options = SmallCar2d();
  options.runs.front().matcher = Matcher::kOptimal;
  options.out = dir / "eval";
  options.report = true;
  options.report_png = false;
  options.errors = ErrorAnalysisOptions{};
  const EvaluationResult result = RunEvaluation(options);
  ASSERT_TRUE(result.runs[0].errors.has_value());
  const EvalInput input = LoadEvalFrames(options.input);
  const std::vector<ErrorAnalysis> expected =
      AnalyzeAllErrors(input.frames, result.runs[0].options, ErrorAnalysisOptions{});
  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["error_analysis"]["background_overlap"], 0.1);
  ASSERT_EQ(j["results"].size(), expected.size());
  std::istringstream csv(ReadFile(options.out / "errors.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line,
            "class,metric,difficulty,overlaps,error,count,delta_ap_r40,delta_ap_r11,ap_r40,ap_r11");
  int checked = 0;
  for (size_t c = 0; c < expected.size(); ++c) {
    const ErrorAnalysis& a = expected[c];
    const nlohmann::json& e = j["results"][c]["errors"];
    EXPECT_EQ(e["ap_r40"], j["results"][c]["ap_r40"]);  // the cell's AP as is
    EXPECT_EQ(e["fp"], a.fp);
    EXPECT_EQ(e["fn"], a.fn);
    for (int t = 0; t < kNumErrorTypes; ++t) {
      const char* name = ErrorTypeName(static_cast<ErrorType>(t));
      EXPECT_EQ(e["count"][name], a.count[t]) << name;
      EXPECT_EQ(e["delta_ap_r40"][name].get<double>(), a.delta_ap_r40[t]) << name;
      std::getline(csv, line);
      const std::vector<std::string> f = SplitCsvLine(line);
      ASSERT_EQ(f.size(), 10u) << line;
      EXPECT_EQ(f[0], "Car");
      EXPECT_EQ(f[4], name);
      EXPECT_EQ(std::stoll(f[5]), a.count[t]);
      EXPECT_EQ(std::stod(f[6]), a.delta_ap_r40[t]);
    }
    EXPECT_EQ(e["special"]["fp_r40"].get<double>(), a.delta_fp_r40);
    EXPECT_EQ(e["special"]["fn_r40"].get<double>(), a.delta_fn_r40);
    std::getline(csv, line);
    EXPECT_THAT(line, HasSubstr(",fp,,"));
    std::getline(csv, line);
    EXPECT_THAT(line, HasSubstr(",fn,,"));
    ++checked;
  }
  EXPECT_EQ(checked, 3);
  EXPECT_FALSE(std::getline(csv, line));
  EXPECT_THAT(FormatEvalTable(result.runs), HasSubstr("Error analysis (TIDE"));
  EXPECT_TRUE(fs::exists(options.out / "report/figures/errors_car_2d_moderate.svg"));

  // Without --errors: no key, no file.
  options.errors.reset();
  RunEvaluation(options);
  EXPECT_FALSE(
      nlohmann::json::parse(ReadFile(options.out / "results.json")).contains("error_analysis"));
  EXPECT_FALSE(fs::exists(options.out / "errors.csv"));
  options.errors = ErrorAnalysisOptions{};
  options.runs.front().compat = EvalCompat::kOpenPcdet;
  EXPECT_THROW(RunEvaluation(options), std::invalid_argument);
}

// --bootstrap with --breakdown: each bin of each cell's "breakdown" carries its intervals, whose
// estimates are the bin's own figures (null where the bin has none); the table's bootstrap block
// has a line per bin under its cell.
TEST(RunEvaluationTest, BootstrapIntervalsOfBreakdownBins) {
  TestTempDir dir;
  EvaluationOptions options = SmallCar2d();
  options.out = dir / "eval";
  options.runs.front().breakdowns = {ParseBreakdown("height=0,40,inf")};
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 40;
  bootstrap.seed = 5;
  options.bootstrap = bootstrap;
  const EvaluationResult result = RunEvaluation(options);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  int checked = 0;
  for (const nlohmann::json& cell : j["results"]) {
    ASSERT_TRUE(cell.contains("breakdown")) << cell.dump();
    ASSERT_EQ(cell["breakdown"].size(), 2u);
    for (const nlohmann::json& bin : cell["breakdown"]) {
      ASSERT_TRUE(bin.contains("bootstrap")) << bin.dump();
      const nlohmann::json& b = bin["bootstrap"];
      EXPECT_EQ(b["ap_r40"]["estimate"], bin["ap_r40"]);
      EXPECT_EQ(b["ap_r11"]["estimate"], bin["ap_r11"]);
      EXPECT_EQ(b["brier_labels"]["estimate"], bin["brier_over_labels"]);
      EXPECT_EQ(b["brier_detections"]["estimate"], bin["brier_over_detections"]);
      EXPECT_EQ(b["brier_all"]["estimate"], bin["brier_over_all"]);
      EXPECT_FALSE(b.contains("ap_voc"));
      if (!b["ap_r40"]["lower"].is_null()) {
        EXPECT_LE(b["ap_r40"]["lower"].get<double>(), b["ap_r40"]["upper"].get<double>());
        EXPECT_GT(b["ap_r40"]["resamples_defined"].get<int>(), 0);
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 3);  // every cell has a bin with intervals
  const std::string table = FormatEvalTable(result.runs);
  EXPECT_THAT(table, ::testing::ContainsRegex(
                         "\nCar +2d +Moderate +[|] [^\n]+\n +height [[]0, 40[)] +[|] "
                         "[-0-9.]+ [[][-0-9.]+, [-0-9.]+[]] +[-0-9.]+ [[][^\n]+\n +height "
                         "[[]40, inf[)] +[|] "));
}

// --breakdown-naive: breakdown.csv's naive_* columns are each bin's "naive" figures of results.json
// (rows in results.json's order of cells and bins); without it they are empty.
TEST(RunEvaluationTest, BreakdownCsvHoldsTheNaiveBins) {
  TestTempDir dir;
  EvaluationOptions options = SmallCar2d();
  options.out = dir / "eval";
  options.runs.front().metrics = {OverlapKind::k2D, OverlapKind::k3D};
  options.runs.front().breakdowns = {ParseBreakdown("distance=0,20,40,inf")};
  for (bool naive : {true, false}) {
    options.runs.front().breakdown_naive = naive;
    RunEvaluation(options);
    const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
    std::istringstream csv(ReadFile(options.out / "breakdown.csv"));
    std::string line;
    std::getline(csv, line);
    const std::vector<std::string> header = SplitCsvLine(line);
    auto column = [&](const std::string& name) {
      const auto it = std::find(header.begin(), header.end(), name);
      EXPECT_NE(it, header.end()) << name;
      return static_cast<size_t>(it - header.begin());
    };
    int rows = 0, with_detections = 0;
    for (const nlohmann::json& cell : j["results"]) {
      for (const nlohmann::json& bin : cell["breakdown"]) {
        ASSERT_TRUE(std::getline(csv, line));
        const std::vector<std::string> f = SplitCsvLine(line);
        ASSERT_EQ(f.size(), header.size()) << line;
        EXPECT_EQ(std::stod(f[column("lower")]), bin["lower"].get<double>());
        if (!naive) {
          for (const char* name : {"naive_num_valid_labels", "naive_ap_r40", "naive_tp", "naive_fp",
                                   "naive_fn", "naive_precision", "naive_recall"}) {
            EXPECT_EQ(f[column(name)], "") << name << ": " << line;
          }
          ++rows;
          continue;
        }
        const nlohmann::json& n = bin["naive"];
        EXPECT_EQ(f[column("naive_num_valid_labels")],
                  std::to_string(n["num_valid_labels"].get<int64_t>()));
        EXPECT_EQ(f[column("naive_tp")], std::to_string(n["at_threshold"]["tp"].get<int64_t>()));
        EXPECT_EQ(f[column("naive_fp")], std::to_string(n["at_threshold"]["fp"].get<int64_t>()));
        EXPECT_EQ(f[column("naive_fn")], std::to_string(n["at_threshold"]["fn"].get<int64_t>()));
        // The shortest text that reads back as the double (fmt's "{}"): equal after reading.
        if (n["ap_r40"].is_null()) {
          EXPECT_EQ(f[column("naive_ap_r40")], "");
        } else {
          EXPECT_EQ(std::stod(f[column("naive_ap_r40")]), n["ap_r40"].get<double>());
        }
        with_detections +=
            n["at_threshold"]["tp"].get<int64_t>() + n["at_threshold"]["fp"].get<int64_t>() > 0;
        ++rows;
      }
    }
    EXPECT_FALSE(std::getline(csv, line)) << "a row beyond results.json's bins: " << line;
    EXPECT_EQ(rows, 2 * 3 * 3);  // 2 overlap kinds x 3 difficulties x 3 bins
    if (naive) {
      EXPECT_GT(with_detections, 0);  // the naive figures are there, not only zeros
    }
  }
}

// eval compare --bootstrap: the paired intervals in OUT/bootstrap.csv; A vs A is exactly zero.
TEST(RunEvaluationCompareTest, PairedBootstrapCsv) {
  TestTempDir dir;
  EvaluationCompareOptions options;
  options.input.gt = kData / "eval_small";
  options.input.det = kData / "eval_small/det";
  options.det_b = kData / "eval_small/det";
  options.eval.classes = {KittiClassSpec("Car")};
  options.eval.metrics = {OverlapKind::k2D};
  options.out = dir / "compare";
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 40;
  options.bootstrap = bootstrap;
  const EvaluationCompareResult result = RunEvaluationCompare(options);
  ASSERT_TRUE(result.bootstrap.has_value());
  EXPECT_EQ(result.bootstrap_csv_path, options.out / "bootstrap.csv");
  const std::string csv = ReadFile(result.bootstrap_csv_path);
  EXPECT_EQ(csv, result.bootstrap_csv);
  // Header + 3 difficulties x 5 metrics (no ap_voc with the KITTI matcher).
  EXPECT_EQ(CountLines(csv), 1 + 3 * 5);
  EXPECT_THAT(csv, HasSubstr("Car,2d,Moderate,ap_r40,15.77"));
  // A - B and its interval are 0, defined in every resample.
  EXPECT_THAT(csv, ::testing::ContainsRegex("Car,2d,Moderate,ap_r40,[0-9.,]*,0,0,0,40,40,0.95,1"));
  for (const BootstrapCell& cell : result.bootstrap->difference.cells) {
    EXPECT_EQ(cell.Get(BootstrapMetric::kApR40).lower, 0.0);
    EXPECT_EQ(cell.Get(BootstrapMetric::kApR40).upper, 0.0);
  }
  EXPECT_TRUE(result.bootstrap_breakdown_path.empty());  // no --breakdown, no bins' file

  // With breakdowns: every bin's paired A - B in OUT/bootstrap_breakdown.csv (A vs A: 0 wherever
  // defined) and a line per bin under each cell in the printed block.
  options.eval.breakdowns = {ParseBreakdown("height=0,40,inf")};
  const EvaluationCompareResult bins = RunEvaluationCompare(options);
  EXPECT_EQ(ReadFile(options.out / "bootstrap.csv"), csv);  // the cells' file unchanged
  ASSERT_EQ(bins.bootstrap_breakdown_path, options.out / "bootstrap_breakdown.csv");
  const std::string bin_csv = ReadFile(bins.bootstrap_breakdown_path);
  // Header + 3 difficulties x 2 bins x 5 metrics.
  EXPECT_EQ(CountLines(bin_csv), 1 + 3 * 2 * 5);
  EXPECT_THAT(bin_csv, HasSubstr("class,metric,difficulty,axis,lower,upper,measure,a,"));
  EXPECT_THAT(bin_csv, HasSubstr("Car,2d,Moderate,height,40,,ap_r40,"));
  int zero = 0;
  for (const BootstrapCell& cell : bins.bootstrap->difference.cells) {
    ASSERT_EQ(cell.breakdown.size(), 2u);
    for (const BootstrapBin& bin : cell.breakdown) {
      const BootstrapInterval& i = bin.Get(BootstrapMetric::kApR40);
      if (i.num_defined == 0) continue;
      EXPECT_EQ(i.estimate, 0.0);
      EXPECT_EQ(i.lower, 0.0);
      EXPECT_EQ(i.upper, 0.0);
      ++zero;
    }
  }
  EXPECT_GT(zero, 0);
  EXPECT_THAT(FormatPairedBootstrapTable(*bins.bootstrap), HasSubstr("height [40, inf) |"));
}

}  // namespace
}  // namespace stereodet
