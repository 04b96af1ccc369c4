#include "stereodet/report/coco_report.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "stereodet/eval/coco.h"
#include "stereodet/pipelines/coco_evaluation.h"
#include "stereodet/report/html_report.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;

const fs::path kCocoSmall = ::stereodet::TestSourceDir() / "tests/data/coco_small";

// tests/data/coco_small evaluated into `out` with the operating-point metrics and, when
// `resamples` > 0, a bootstrap over images.
CocoEvaluationResult EvaluateCocoSmall(const fs::path& out, int resamples) {
  CocoEvaluationOptions options;
  options.gt = kCocoSmall / "gt.json";
  options.det = kCocoSmall / "det.json";
  options.eval.score_metrics = true;
  if (resamples > 0) {
    options.bootstrap.emplace();
    options.bootstrap->num_resamples = resamples;
  }
  options.out = out;
  return RunCocoEvaluation(options);
}

// The curves are summarize()'s averages of the precision array, read back from precision.npy: at
// IoU 0.5 the mean over the categories with ground truth, and over all thresholds the mean whose
// own mean over recall is AP@[.50:.95].
TEST(CocoReportTest, CurvesAreTheMeansOfThePrecisionArray) {
  TestTempDir dir;
  const CocoEvaluationResult run = EvaluateCocoSmall(dir.path() / "eval", 0);
  const CocoEvalResult& r = run.result;
  const ReportSource source = ReadReportSource(dir.path() / "eval", "a");
  ASSERT_EQ(source.kind, ReportKind::kCoco);
  const json& pr = source.results["report_pr"];
  const size_t R = r.options.recall_thresholds.size(), K = r.category_ids.size();
  ASSERT_EQ(pr["recall"].size(), R);
  const int m = static_cast<int>(r.options.max_dets.size()) - 1;
  double mean_of_mean = 0;
  for (size_t rr = 0; rr < R; ++rr) {
    double sum = 0;
    int n = 0;
    for (size_t k = 0; k < K; ++k) {
      const double v =
          r.precision[r.PrecisionIndex(0, static_cast<int>(rr), static_cast<int>(k), 0, m)];
      if (v > -1) {
        sum += v;
        ++n;
      }
    }
    ASSERT_GT(n, 0);
    EXPECT_NEAR(pr["AP50"][rr].get<double>(), sum / n, 1e-15) << "recall threshold " << rr;
    mean_of_mean += pr["AP"][rr].get<double>();
  }
  EXPECT_NEAR(mean_of_mean / static_cast<double>(R), r.stats[0], 1e-12);
}

// Pooling the reliability over categories, by hand: two categories' counts 2 and 1 in a bin with
// mean scores 0.3 and 0.6 and TP fractions 0.5 and 1 give 3 detections, mean score 0.4 and TP
// fraction 2/3; rows at IoU 0.75 or another area are left out, an empty bin has no point.
TEST(CocoReportTest, ReliabilityIsPooledOverCategoriesByCount) {
  TestTempDir dir;
  EvaluateCocoSmall(dir.path() / "eval", 0);
  WriteFileAtomically(dir.path() / "eval/reliability.csv",
                      "iou,category_id,area,lower,upper,count,mean_score,tp_fraction\n"
                      "0.5,1,all,0.2,0.4,2,0.3,0.5\n"
                      "0.5,2,all,0.2,0.4,1,0.6,1\n"
                      "0.5,1,all,0.4,0.6,0,nan,nan\n"
                      "0.75,1,all,0.2,0.4,5,0.3,0\n"
                      "0.5,1,small,0.2,0.4,5,0.3,0\n");
  const ReportSource source = ReadReportSource(dir.path() / "eval", "a");
  const json& rel = source.results["report_reliability"];
  ASSERT_EQ(rel["count"].size(), 2u);
  EXPECT_DOUBLE_EQ(rel["count"][0].get<double>(), 3);
  EXPECT_DOUBLE_EQ(rel["mean_score"][0].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(rel["tp_fraction"][0].get<double>(), 2.0 / 3);
  EXPECT_TRUE(rel["mean_score"][1].is_null());
}

// The page: the three PR figures, the 12 numbers with their intervals, the categories and the
// reliability; two folders overlaid get a series each.
TEST(CocoReportTest, PageHoldsTheCocoFiguresAndTables) {
  TestTempDir dir;
  const CocoEvaluationResult run = EvaluateCocoSmall(dir.path() / "eval", 30);
  EvaluateCocoSmall(dir.path() / "eval2", 0);
  ReportOptions options;
  options.results = {dir.path() / "eval", dir.path() / "eval2"};
  options.out = dir.path() / "report";
  options.png = false;
  const ReportResult report = WriteReport(options);
  EXPECT_EQ(report.num_figures, 6);
  const std::string html = ReadFile(report.index);
  for (const char* id : {"coco_pr_50", "coco_pr_75", "coco_pr_mean", "coco_stats",
                         "coco_categories", "coco_reliability"}) {
    EXPECT_THAT(html, HasSubstr(std::string("id=\"fig-") + id + "\"")) << id;
    EXPECT_TRUE(fs::is_regular_file(options.out / "figures" / (std::string(id) + ".svg"))) << id;
  }
  EXPECT_THAT(html, HasSubstr("(COCO mode)"));
  // The first folder's AP with its bootstrap interval, as the summary table shows it.
  const BootstrapInterval& ap = run.bootstrap->stats[0];
  EXPECT_THAT(html, HasSubstr(fmt::format("<td>{:.3f} <small>[{:.3f}, {:.3f}]</small></td>",
                                          run.result.stats[0], ap.lower, ap.upper)));
  const json figures =
      json::parse(html.substr(html.find("id=\"stereodet-figures\">") + 23,
                              html.find("</script>", html.find("id=\"stereodet-figures\"")) -
                                  html.find("id=\"stereodet-figures\">") - 23));
  for (const json& f : figures) {
    if (f["id"] == "coco_pr_50") {
      EXPECT_EQ(f["series"].size(), 2u);
    }
    if (f["id"] == "coco_stats") {
      // Whiskers for the folder with a bootstrap, none for the other.
      EXPECT_FALSE(f["series"][0]["y_low"][0].is_null());
      EXPECT_TRUE(f["series"][1]["y_low"].empty() || f["series"][1]["y_low"][0].is_null());
    }
  }
}

TEST(CocoReportTest, APrecisionArrayOfTheWrongShapeIsRefusedNamingTheFile) {
  TestTempDir dir;
  EvaluateCocoSmall(dir.path() / "eval", 0);
  const std::string npy = ReadFile(dir.path() / "eval/precision.npy");
  WriteFileAtomically(dir.path() / "eval/precision.npy", npy.substr(0, npy.size() - 8));
  try {
    ReadReportSource(dir.path() / "eval", "a");
    FAIL() << "a cut precision.npy was read";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("precision.npy"));
    EXPECT_THAT(e.what(), HasSubstr("bytes of data"));
  }
}

}  // namespace
}  // namespace stereodet
