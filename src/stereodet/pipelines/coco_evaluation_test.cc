#include "stereodet/pipelines/coco_evaluation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Two images, two categories: each box of category 1 found exactly; category 2 has no ground truth,
// only a detection.
constexpr char kGt[] = R"({
  "images": [{"id": 1}, {"id": 2}],
  "categories": [{"id": 1, "name": "person"}, {"id": 2, "name": "bicycle"}],
  "annotations": [
    {"id": 1, "image_id": 1, "category_id": 1, "bbox": [0, 0, 4, 9], "area": 36, "iscrowd": 0},
    {"id": 2, "image_id": 2, "category_id": 1, "bbox": [10, 10, 40, 40], "area": 1600,
     "iscrowd": 0}]})";
constexpr char kDet[] = R"([
  {"image_id": 1, "category_id": 1, "bbox": [0, 0, 4, 9], "score": 0.9},
  {"image_id": 2, "category_id": 1, "bbox": [10, 10, 40, 40], "score": 0.8},
  {"image_id": 2, "category_id": 2, "bbox": [0, 0, 5, 5], "score": 0.3}])";

struct Inputs {
  TestTempDir dir;
  fs::path gt, det;
  Inputs() : gt(dir.path() / "gt.json"), det(dir.path() / "det.json") {
    WriteFileAtomically(gt, kGt);
    WriteFileAtomically(det, kDet);
  }
};

// The shape and values of a .npy file of float64 that NpyFloat64 wrote.
struct Npy {
  std::string header;
  std::vector<double> values;
};

Npy ReadNpy(const fs::path& path) {
  const std::string bytes = ReadFile(path);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  const size_t header_size =
      static_cast<unsigned char>(bytes[8]) | static_cast<unsigned char>(bytes[9]) << 8;
  EXPECT_EQ((10 + header_size) % 64, 0u);
  Npy npy;
  npy.header = bytes.substr(10, header_size);
  npy.values.resize((bytes.size() - 10 - header_size) / sizeof(double));
  std::memcpy(npy.values.data(), bytes.data() + 10 + header_size,
              npy.values.size() * sizeof(double));
  return npy;
}

TEST(CocoEvaluationTest, WritesResultsJsonAndNumpyArrays) {
  Inputs in;
  CocoEvaluationOptions options;
  options.gt = in.gt;
  options.det = in.det;
  options.out = in.dir.path() / "eval";
  options.command_line = "stereodet eval --coco-gt gt.json --coco-det det.json";
  const CocoEvaluationResult run = RunCocoEvaluation(options);
  EXPECT_EQ(run.files.size(), 4u);
  EXPECT_NEAR(run.result.stats[0], 1.0, 1e-15);

  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["mode"], "coco");
  EXPECT_EQ(j["command_line"], options.command_line);
  EXPECT_EQ(j["input"]["num_images"], 2);
  EXPECT_EQ(j["input"]["num_gt"], 2);
  EXPECT_EQ(j["input"]["num_detections"], 3);
  EXPECT_EQ(j["input_hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(j["stats"]["AP"].get<double>(), run.result.stats[0]);
  EXPECT_EQ(j["stats"]["APs"].get<double>(), run.result.stats[3]);  // the 36 px^2 box
  EXPECT_EQ(j["stats"]["APl"].get<double>(), -1.0);
  EXPECT_EQ(j["categories"][1]["name"], "bicycle");
  EXPECT_EQ(j["categories"][0]["stats"]["AP"].get<double>(), run.result.stats[0]);
  EXPECT_EQ(j["categories"][1]["stats"]["AP"].get<double>(), -1.0);  // no ground truth
  EXPECT_EQ(j["options"]["iou_thresholds"][8].get<double>(), 0.8999999999999999);
  EXPECT_EQ(j["arrays"]["precision"]["shape"], nlohmann::json({10, 101, 2, 4, 3}));

  const Npy precision = ReadNpy(options.out / "precision.npy");
  EXPECT_THAT(precision.header,
              HasSubstr("{'descr': '<f8', 'fortran_order': False, 'shape': (10, 101, 2, 4, 3), }"));
  EXPECT_EQ(precision.values, run.result.precision);
  const Npy recall = ReadNpy(options.out / "recall.npy");
  EXPECT_THAT(recall.header, HasSubstr("'shape': (10, 2, 4, 3), }"));
  EXPECT_EQ(recall.values, run.result.recall);
  EXPECT_EQ(ReadNpy(options.out / "scores.npy").values, run.result.scores);

  // A second run replaces the folder; a folder holding an input is refused before any work.
  EXPECT_NO_THROW(RunCocoEvaluation(options));
  options.out = in.dir.path();
  try {
    RunCocoEvaluation(options);
    ADD_FAILURE() << "an output folder holding the inputs was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("holds the input --coco-gt"));
  }
}

// With the operating-point metrics: the 12 numbers by name, cells.csv (one row per IoU threshold,
// category and area range) and reliability.csv (calibration_bins rows per cell).
TEST(CocoEvaluationTest, ScoreMetricsWriteCellsAndReliability) {
  Inputs in;
  CocoEvaluationOptions options;
  options.gt = in.gt;
  options.det = in.det;
  options.out = in.dir.path() / "eval";
  options.eval.matcher = CocoMatcher::kOptimal;
  options.eval.score_metrics = true;
  options.eval.calibration_bins = 5;
  const CocoEvaluationResult run = RunCocoEvaluation(options);
  EXPECT_EQ(run.files.size(), 6u);
  const nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["options"]["matcher"], "optimal");
  EXPECT_TRUE(j["options"]["score_threshold"].is_null());  // -inf: every detection
  EXPECT_EQ(j["options"]["calibration_bins"], 5);
  EXPECT_TRUE(j["probability_metrics"].get<bool>());
  // Category 1: scores 0.9 and 0.8 on their boxes at every threshold; category 2 has no ground
  // truth (no label term) and one FP at 0.3, which only the detection terms see.
  EXPECT_NEAR(j["score_stats"]["BL"].get<double>(), (0.01 + 0.04) / 2, 1e-15);
  EXPECT_EQ(j["score_stats"]["BL"].get<double>(), run.result.score_stats[0]);
  EXPECT_NEAR(j["score_stats"]["BD"].get<double>(), ((0.01 + 0.04) / 2 + 0.09) / 2, 1e-15);
  const std::string cells = ReadFile(options.out / "cells.csv");
  EXPECT_EQ(std::count(cells.begin(), cells.end(), '\n'), 1 + 10 * 2 * 4);
  EXPECT_THAT(cells, HasSubstr("0.5,1,all,2,2,0,0,1,1,1,0.0249999"));  // (0.01 + 0.04) / 2
  EXPECT_THAT(cells, HasSubstr("0.5,2,all,0,0,1,0,0,0,0,nan,0.09,0.09,"));
  // LaECE: category 1's two TPs (0.9, 0.8) on their boxes (IoU 1) share the bin [0.8, 1): |0.85 -
  // 1| = 0.15, as the ECE; category 2's lone FP at 0.3 (IoU 0): |0.3 - 0| = 0.3.
  {
    std::istringstream lines(cells);
    std::string line;
    std::getline(lines, line);
    const std::vector<std::string_view> header = Split(line, ',');
    const size_t laece =
        static_cast<size_t>(std::find(header.begin(), header.end(), "laece") - header.begin());
    ASSERT_LT(laece, header.size()) << line;
    int found = 0;
    while (std::getline(lines, line)) {
      const std::vector<std::string_view> f = Split(line, ',');
      if (f[0] != "0.5" || f[2] != "all") continue;
      const double expected = f[1] == "1" ? 0.15 : 0.3;
      EXPECT_NEAR(std::stod(std::string(f[laece])), expected, 1e-12) << line;
      ++found;
    }
    EXPECT_EQ(found, 2);
  }
  const std::string reliability = ReadFile(options.out / "reliability.csv");
  EXPECT_EQ(std::count(reliability.begin(), reliability.end(), '\n'), 1 + 10 * 2 * 4 * 5);
  EXPECT_THAT(reliability, HasSubstr("0.5,2,all,0.2,0.4,1,0.3,0\n"));
}

// --bootstrap: intervals in results.json; --coco-det-b: B's numbers, A - B and the paired
// intervals (A against itself: exactly 0).
TEST(CocoEvaluationTest, BootstrapAndCompare) {
  Inputs in;
  CocoEvaluationOptions options;
  options.gt = in.gt;
  options.det = in.det;
  options.out = in.dir.path() / "eval";
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 50;
  options.bootstrap = bootstrap;
  const CocoEvaluationResult run = RunCocoEvaluation(options);
  ASSERT_TRUE(run.bootstrap.has_value());
  EXPECT_FALSE(run.paired.has_value());
  nlohmann::json j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["bootstrap"]["num_resamples"], 50);
  EXPECT_EQ(j["bootstrap"]["num_images"], 2);
  EXPECT_EQ(j["bootstrap"]["stats"]["AP"]["estimate"].get<double>(), run.result.stats[0]);
  EXPECT_EQ(j["bootstrap"]["stats"]["AP"]["num_defined"], 50);  // every resample has a box
  EXPECT_THAT(FormatCocoBootstrap(*run.bootstrap),
              HasSubstr("bootstrap: 50 resamples of the 2 images (seed 1), 95% percentile"));
  EXPECT_THAT(FormatCocoBootstrap(*run.bootstrap), HasSubstr("\nAPl    -1 (no ground truth)\n"));

  options.det_b = in.det;
  const CocoEvaluationResult paired = RunCocoEvaluation(options);
  ASSERT_TRUE(paired.paired.has_value() && paired.result_b.has_value());
  j = nlohmann::json::parse(ReadFile(options.out / "results.json"));
  EXPECT_EQ(j["compare"]["stats_b"]["AP"].get<double>(), run.result.stats[0]);
  EXPECT_EQ(j["compare"]["difference"]["AP"].get<double>(), 0.0);
  EXPECT_TRUE(j["compare"]["difference"]["APl"].is_null());
  EXPECT_EQ(j["compare"]["paired_bootstrap"]["stats"]["AP"]["lower"].get<double>(), 0.0);
  EXPECT_EQ(j["compare"]["paired_bootstrap"]["stats"]["AP"]["upper"].get<double>(), 0.0);
  EXPECT_THAT(FormatCocoCompare(paired.result, *paired.result_b, &*paired.paired),
              HasSubstr("AP     A  1.000  B  1.000  A - B +0.000 [+0.000, +0.000]\n"));
  EXPECT_THAT(FormatCocoCompare(paired.result, *paired.result_b, nullptr),
              HasSubstr("APl    A -1.000  B -1.000  A - B undefined (no ground truth)\n"));
}

TEST(CocoEvaluationTest, WithoutOutWritesNothingAndReportsBadFiles) {
  Inputs in;
  CocoEvaluationOptions options;
  options.gt = in.gt;
  options.det = in.det;
  const CocoEvaluationResult run = RunCocoEvaluation(options);
  EXPECT_TRUE(run.files.empty());
  EXPECT_EQ(run.result.category_ids.size(), 2u);

  WriteFileAtomically(in.det, R"([{"image_id": 5, "category_id": 1, "bbox": [0, 0, 1, 1],
                                   "score": 0.5}])");
  try {
    RunCocoEvaluation(options);
    ADD_FAILURE() << "a detection on an image of another data set was accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), in.det.string());
    EXPECT_EQ(e.field(), "[0].image_id");
  }
  options.det.clear();
  EXPECT_THROW(RunCocoEvaluation(options), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
