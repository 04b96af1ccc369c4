#include "stereodet/report/html_report.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/pipelines/evaluation.h"
#include "stereodet/report/raster.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/test_paths.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

const fs::path kData = ::stereodet::TestSourceDir() / "tests/data";

// tests/data/eval_small with the KITTI matcher (41-slot arrays) or the optimal one, every class,
// metric and difficulty (or Car 2D only), written with its report (SVG only unless `png`).
// `eval compare` of tests/data/eval_compare's two detection sets, Car 2D (set out before running).
EvaluationCompareOptions CarCompareOptions() {
  EvaluationCompareOptions compare;
  compare.input.gt = kData / "eval_compare";
  compare.input.det = kData / "eval_compare/det_a";
  compare.det_b = kData / "eval_compare/det_b";
  compare.eval.classes = {KittiClassSpec("Car")};
  compare.eval.metrics = {OverlapKind::k2D};
  return compare;
}

EvaluationResult EvaluateSmall(const fs::path& out, Matcher matcher, bool png = false,
                               bool car_2d_only = false) {
  EvaluationOptions options;
  options.input.gt = kData / "eval_small";
  options.input.det = kData / "eval_small/det";
  options.runs.front().matcher = matcher;
  options.out = out;
  options.report = true;
  options.report_png = png;
  if (car_2d_only) {
    options.runs.front().classes = {KittiClassSpec("Car")};
    options.runs.front().metrics = {OverlapKind::k2D};
  }
  return RunEvaluation(options);
}

json SvgData(const fs::path& svg_path) {
  const std::string svg = ReadFile(svg_path);
  const size_t begin = svg.find("<![CDATA[") + 9;
  const size_t end = svg.find("]]></metadata>");
  return json::parse(svg.substr(begin, end - begin));
}

std::vector<double> Column(const json& j) {
  std::vector<double> v;
  for (const json& x : j) v.push_back(x.is_null() ? NAN : x.get<double>());
  return v;
}

// Equal element for element, NaN equal to NaN (not computed on both sides).
::testing::AssertionResult SameNumbers(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) {
    return ::testing::AssertionFailure() << a.size() << " vs " << b.size() << " numbers";
  }
  for (size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) {
      return ::testing::AssertionFailure() << "at " << i << ": " << a[i] << " vs " << b[i];
    }
  }
  return ::testing::AssertionSuccess();
}

// The columns of a CSV file with a header row, as numbers.
std::map<std::string, std::vector<double>> ReadCsv(const fs::path& path) {
  std::istringstream in(ReadFile(path));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    size_t i = 0;
    for (const std::string_view cell_view : Split(line, ',')) {  // empty cells kept, a last one too
      // Text (a class name), "-" and empty cells are NaN here.
      const std::string cell(cell_view);
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      columns[names.at(i++)].push_back(cell.empty() || *end != '\0' ? NAN : v);
    }
  }
  return columns;
}

// As the figures print a number: fixed decimals, "-" for null (not computed).
std::string Fixed(const json& v, int decimals) {
  return v.is_number() ? fmt::format("{:.{}f}", v.get<double>(), decimals) : "-";
}

const json& Entry(const json& results, const std::string& cls, const std::string& metric,
                  const std::string& difficulty) {
  for (const json& e : results["results"]) {
    if (e["class"] == cls && e["metric"] == metric && e["difficulty"] == difficulty) return e;
  }
  throw std::logic_error("no entry " + cls + " " + metric + " " + difficulty);
}

// Every figure's plotted numbers are results.json's: the PR and ROC curves point for point, the
// devkit's 41 slots, the reliability bins, the Brier scores and the localization medians.
TEST(ReportTest, FiguresPlotTheCurvesOfResultsJson) {
  TestTempDir dir;
  const fs::path out = dir.path() / "eval";
  const EvaluationResult evaluation = EvaluateSmall(out, Matcher::kKitti);
  EXPECT_EQ(evaluation.report_index, out / "report/index.html");
  // results.json names each cell's curve CSV; the report reads it as "curve".
  const json results = ReadReportSource(out, "kitti").results;
  int checked_pr = 0, checked_devkit = 0, checked_reliability = 0, checked_localization = 0,
      checked_no_labels = 0;
  for (const json& e : results["results"]) {
    if (!e["evaluated"].get<bool>()) continue;
    std::string stem = e["class"].get<std::string>() + "_" + e["metric"].get<std::string>() + "_" +
                       e["difficulty"].get<std::string>();
    for (char& c : stem) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const fs::path figures = out / "report/figures";
    const json pr = SvgData(figures / ("pr_" + stem + ".svg"));
    EXPECT_EQ(pr["series"][0]["x"], e["curve"]["recall"]) << stem;
    EXPECT_EQ(pr["series"][0]["y"], e["curve"]["precision"]) << stem;
    // The devkit's slots, at recall i/40.
    ASSERT_EQ(pr["series"].size(), 2u) << stem;
    EXPECT_EQ(pr["series"][1]["y"], e["kitti"]["precision"]) << stem;
    ASSERT_EQ(pr["series"][1]["x"].size(), 41u);
    EXPECT_EQ(pr["series"][1]["x"][40], 1.0);
    EXPECT_EQ(pr["series"][1]["x"][10], 0.25);
    ++checked_devkit;
    // The legend carries the APs of results.json, "-" where the cell has no valid label (the
    // devkit's 0 there is no detector's score).
    const bool no_labels = e["num_valid_labels"].get<int>() == 0;
    EXPECT_THAT(pr["series"][0]["name"].get<std::string>(),
                HasSubstr("AP_R40 " + (no_labels ? std::string("-") : Fixed(e["ap_r40"], 2))));
    checked_no_labels += no_labels;
    if (no_labels) {
      EXPECT_THAT(SvgData(figures / ("pr_" + stem + ".svg"))["caption"].get<std::string>(),
                  HasSubstr("no valid label in this cell, so no recall and no AP"));
    }
    // And the curve CSV has the same numbers (full precision in both).
    auto csv = ReadCsv(out / "curves" / ("pr_" + stem + ".csv"));  // no rows: no columns
    EXPECT_EQ(csv["recall"], Column(pr["series"][0]["x"])) << stem;
    EXPECT_EQ(csv["precision"], Column(pr["series"][0]["y"])) << stem;
    ++checked_pr;

    const json roc = SvgData(figures / ("roc_" + stem + ".svg"));
    EXPECT_EQ(roc["series"][0]["x"], e["curve"]["fp_per_frame"]) << stem;
    EXPECT_EQ(roc["series"][0]["y"], e["curve"]["recall"]) << stem;

    const json rel = SvgData(figures / ("reliability_" + stem + ".svg"));
    ASSERT_EQ(rel["series"].size(), 2u);  // the diagonal, then the bins
    const json& bins = e["calibration"]["bins"];
    ASSERT_EQ(rel["series"][1]["x"].size(), bins.size());
    for (size_t b = 0; b < bins.size(); ++b) {
      if (bins[b]["count"].get<int>() == 0) {
        EXPECT_TRUE(rel["series"][1]["y"][b].is_null());
      } else {
        EXPECT_EQ(rel["series"][1]["x"][b], bins[b]["mean_score"]);
        EXPECT_EQ(rel["series"][1]["y"][b], bins[b]["tp_fraction"]);
      }
    }
    EXPECT_THAT(rel["series"][1]["name"].get<std::string>(),
                HasSubstr("ECE " + Fixed(e["calibration"]["ece"], 4)));
    ++checked_reliability;

    const fs::path loc_path = figures / ("localization_" + stem + ".svg");
    bool has_pairs = false;
    for (const json& b : e["localization"]) has_pairs |= b["count"].get<int>() > 0;
    EXPECT_EQ(fs::exists(loc_path), has_pairs) << stem;
    if (has_pairs) {
      const json loc = SvgData(loc_path);
      for (size_t b = 0; b < e["localization"].size(); ++b) {
        const json& bin = e["localization"][b];
        EXPECT_EQ(loc["series"][0]["x"][b],
                  (bin["lower_m"].get<double>() + bin["upper_m"].get<double>()) / 2);
        if (bin["count"].get<int>() > 0) {
          EXPECT_EQ(loc["series"][0]["y"][b], bin["centre_error_median_m"]);
          EXPECT_EQ(loc["series"][0]["y_high"][b], bin["centre_error_p90_m"]);
          EXPECT_EQ(loc["series"][1]["y"][b], bin["abs_depth_error_median_m"]);
        }
      }
      ++checked_localization;
    }
  }
  EXPECT_EQ(checked_pr, 27);  // 3 classes x 3 metrics x 3 difficulties, all evaluated here
  EXPECT_GT(checked_no_labels, 0);
  EXPECT_EQ(checked_devkit, 27);
  EXPECT_EQ(checked_reliability, 27);
  EXPECT_GT(checked_localization, 0);

  // Brier: per class and metric, three bars per difficulty.
  const json brier = SvgData(out / "report/figures/brier_car_2d.svg");
  ASSERT_EQ(brier["series"].size(), 3u);
  EXPECT_EQ(brier["categories"], json({"Easy", "Moderate", "Hard"}));
  const std::vector<std::string> difficulties = {"Easy", "Moderate", "Hard"};
  for (size_t d = 0; d < 3; ++d) {
    const json& b = Entry(results, "Car", "2d", difficulties[d])["brier"];
    EXPECT_EQ(brier["series"][0]["y"][d], b["over_labels"]);
    EXPECT_EQ(brier["series"][1]["y"][d], b["over_detections"]);
    EXPECT_EQ(brier["series"][2]["y"][d], b["over_all"]);
  }

  // Easy, Moderate and Hard in one figure (the devkit's plot), each the cell's exact curve drawn
  // as steps, a colour each; the cell's own PR figure draws its exact curve as steps too.
  const json by_difficulty = SvgData(out / "report/figures/pr_difficulties_car_2d.svg");
  ASSERT_EQ(by_difficulty["series"].size(), 3u);
  for (size_t d = 0; d < 3; ++d) {
    const json& e = Entry(results, "Car", "2d", difficulties[d]);
    const json& s = by_difficulty["series"][d];
    EXPECT_EQ(s["x"], e["curve"]["recall"]) << d;
    EXPECT_EQ(s["y"], e["curve"]["precision"]) << d;
    EXPECT_EQ(s["steps"], true);
    EXPECT_THAT(s["name"].get<std::string>(), HasSubstr(difficulties[d] + ": AP_R40 "));
  }
  const std::string by_difficulty_svg = ReadFile(out / "report/figures/pr_difficulties_car_2d.svg");
  for (const char* colour : {"#0072B2", "#D55E00", "#009E73"}) {
    EXPECT_THAT(by_difficulty_svg, HasSubstr(std::string("stroke=\"") + colour + "\""));
  }
  EXPECT_EQ(SvgData(out / "report/figures/pr_car_2d_moderate.svg")["series"][0]["steps"], true);
}

// eval --breakdown: one figure per cell and axis, a bar per bin holding results.json's AP_R40.
// tests/data/eval_small's Car cells of one overlap kind with one breakdown, and the report (SVG).
EvaluationOptions SmallCarBreakdown(const fs::path& out, OverlapKind kind,
                                    const std::string& breakdown) {
  EvaluationOptions options;
  options.input.gt = kData / "eval_small";
  options.input.det = kData / "eval_small/det";
  options.runs.front().classes = {KittiClassSpec("Car")};
  options.runs.front().metrics = {kind};
  options.runs.front().breakdowns = {ParseBreakdown(breakdown)};
  options.out = out;
  options.report = true;
  options.report_png = false;
  return options;
}

TEST(ReportTest, BreakdownFigurePlotsApR40PerBin) {
  TestTempDir dir;
  const fs::path out = dir.path() / "eval";
  EvaluationOptions options = SmallCarBreakdown(out, OverlapKind::k2D, "height=0,40,inf");
  RunEvaluation(options);
  const json results = ReadReportSource(out, "kitti").results;
  const json& e = Entry(results, "Car", "2d", "Moderate");
  ASSERT_EQ(e["breakdown"].size(), 2u);
  const json figure = SvgData(out / "report/figures/breakdown_height_car_2d_moderate.svg");
  EXPECT_EQ(figure["categories"], json({"[0, 40)", "[40, inf)"}));
  ASSERT_EQ(figure["series"].size(), 1u);
  for (size_t b = 0; b < 2; ++b) {
    EXPECT_EQ(figure["series"][0]["y"][b], e["breakdown"][b]["ap_r40"]) << b;
  }
  EXPECT_THAT(ReadFile(out / "report/index.html"), HasSubstr("AP_R40 by height"));
  EXPECT_FALSE(figure["series"][0].contains("y_low"));  // no bootstrap, no whiskers

  // With --bootstrap each bar has its interval as a whisker, results.json's, on the bar.
  options.bootstrap = BootstrapOptions{};
  options.bootstrap->num_resamples = 50;
  options.out = dir.path() / "bootstrap";
  RunEvaluation(options);
  const json with = ReadReportSource(options.out, "kitti").results;
  const json& eb = Entry(with, "Car", "2d", "Moderate");
  const json fb = SvgData(options.out / "report/figures/breakdown_height_car_2d_moderate.svg");
  int whiskers = 0;
  for (size_t b = 0; b < 2; ++b) {
    const json& interval = eb["breakdown"][b]["bootstrap"]["ap_r40"];
    EXPECT_EQ(fb["series"][0]["y_low"][b], interval["lower"]) << b;
    EXPECT_EQ(fb["series"][0]["y_high"][b], interval["upper"]) << b;
    whiskers += !interval["lower"].is_null();
  }
  EXPECT_GT(whiskers, 0);
  const std::string svg =
      ReadFile(options.out / "report/figures/breakdown_height_car_2d_moderate.svg");
  EXPECT_THAT(svg, HasSubstr("<line class=\"whisker\""));
  EXPECT_THAT(svg, HasSubstr("stroke=\"#222222\""));

  // With --breakdown-naive a second bar series holds each bin's naive AP_R40, results.json's.
  options.bootstrap.reset();
  options.runs.front().breakdown_naive = true;
  options.out = dir.path() / "naive";
  RunEvaluation(options);
  const json with_naive = ReadReportSource(options.out, "kitti").results;
  const json& en = Entry(with_naive, "Car", "2d", "Moderate");
  const json fn = SvgData(options.out / "report/figures/breakdown_height_car_2d_moderate.svg");
  ASSERT_EQ(fn["series"].size(), 2u);
  for (size_t b = 0; b < 2; ++b) {
    EXPECT_EQ(fn["series"][0]["y"][b], en["breakdown"][b]["ap_r40"]) << b;
    EXPECT_EQ(fn["series"][1]["y"][b], en["breakdown"][b]["naive"]["ap_r40"]) << b;
  }
  EXPECT_THAT(ReadFile(options.out / "report/index.html"), HasSubstr("naive [0, 40)"));
}

// A LET cell's figures carry its LET-APL (the PR legend; a bar per breakdown bin beside the AP),
// and every reliability figure its LaECE and D-ECE, each results.json's number.
TEST(ReportTest, LetCellsShowAplAndReliabilityFiguresShowLaeceAndDece) {
  TestTempDir dir;
  const fs::path out = dir.path() / "eval";
  RunEvaluation(SmallCarBreakdown(out, OverlapKind::kLet3D, "distance=0,20,inf"));
  const json results = ReadReportSource(out, "let").results;
  const json& e = Entry(results, "Car", "let-3d", "Moderate");
  ASSERT_TRUE(e.contains("apl_r40"));
  ASSERT_EQ(e["breakdown"].size(), 2u);
  const json figure = SvgData(out / "report/figures/breakdown_distance_car_let-3d_moderate.svg");
  ASSERT_EQ(figure["series"].size(), 2u);
  EXPECT_THAT(figure["series"][1]["name"].get<std::string>(), HasSubstr("APL_R40"));
  for (size_t b = 0; b < 2; ++b) {
    EXPECT_EQ(figure["series"][0]["y"][b], e["breakdown"][b]["ap_r40"]) << b;
    EXPECT_EQ(figure["series"][1]["y"][b], e["breakdown"][b]["apl_r40"]) << b;
  }
  const json pr = SvgData(out / "report/figures/pr_car_let-3d_moderate.svg");
  EXPECT_THAT(pr["series"][0]["name"].get<std::string>(),
              HasSubstr(fmt::format("APL_R40 {:.2f}", e["apl_r40"].get<double>())));
  const json reliability = SvgData(out / "report/figures/reliability_car_let-3d_moderate.svg");
  const std::string name = reliability["series"][1]["name"].get<std::string>();
  EXPECT_THAT(name,
              HasSubstr(fmt::format("LaECE {:.4f}", e["calibration"]["laece"].get<double>())));
  EXPECT_THAT(name, HasSubstr(fmt::format("D-ECE {:.4f}", e["calibration"]["dece"].get<double>())));
}

// The curves results.json names come back exactly, point for point and bit for bit, as the
// evaluation computed them (the optimal matcher: one point per distinct score; NaN as null).
TEST(ReportTest, ReadReportSourceLoadsTheExactCurvesOfTheCsvsResultsJsonNames) {
  TestTempDir dir;
  const EvaluationResult evaluation = EvaluateSmall(dir.path() / "eval", Matcher::kOptimal);
  const ReportSource source = ReadReportSource(dir.path() / "eval", "optimal");
  const EvalResult& result = evaluation.runs.front().result;
  auto same = [](const json& v, double x) { return std::isnan(x) ? v.is_null() : v == x; };
  int cells = 0;
  for (const ClassResult& r : result.results) {
    if (!r.evaluated) continue;
    const json& e = Entry(source.results, r.class_name, OverlapKindName(r.metric),
                          DifficultyName(r.difficulty));
    const json& c = e["curve"];
    ASSERT_EQ(c["tp"].size(), r.curve.size());
    ASSERT_EQ(e["curve_points"], r.curve.size());
    EXPECT_EQ(c.contains("orientation"), r.has_aos);
    for (size_t i = 0; i < r.curve.size(); ++i) {
      const CurvePoint& p = r.curve[i];
      ASSERT_TRUE(same(c["threshold"][i], p.threshold)) << i;
      ASSERT_EQ(c["tp"][i], p.tp);
      ASSERT_EQ(c["fp"][i], p.fp);
      ASSERT_EQ(c["fn"][i], p.fn);
      ASSERT_TRUE(same(c["precision"][i], p.precision)) << i;
      ASSERT_TRUE(same(c["recall"][i], p.recall)) << i;
      ASSERT_TRUE(same(c["fp_per_frame"][i], static_cast<double>(p.fp) / result.num_frames));
      if (r.has_aos) {
        ASSERT_TRUE(same(c["orientation"][i], p.orientation)) << i;
      }
    }
    ++cells;
  }
  EXPECT_GT(cells, 10);
}

// A results.json with a string where a number belongs is refused naming the field (it gave empty
// cells before).
TEST(ReportTest, AStringWhereANumberBelongsIsRefusedNamingTheField) {
  TestTempDir dir;
  EvaluateSmall(dir.path() / "eval", Matcher::kOptimal);
  const fs::path path = dir.path() / "eval" / "results.json";
  json results = json::parse(ReadFile(path));
  results["results"][0]["ap_r40"] = "0.5";
  WriteFileAtomically(path, results.dump(2));
  try {
    ReadReportSource(dir.path() / "eval", "optimal");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("results[0] ("), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ap_r40 is \"0.5\", not a number"), std::string::npos)
        << e.what();
  }
}

// The pixels agree with the data too: every polyline vertex of the exact PR curve maps back, with
// the figure's frame, to the curve's (recall, precision) within the SVG's 0.01 px rounding.
TEST(ReportTest, AFolderLabelIgnoresTrailingSeparatorsAndDots) {
  EXPECT_EQ(FolderLabel("runs/eval"), "eval");
  EXPECT_EQ(FolderLabel("runs/eval/"), "eval");  // `--out eval/` blanked the label
  EXPECT_EQ(FolderLabel("runs/eval/."), "eval");
  EXPECT_EQ(FolderLabel("eval//"), "eval");
  EXPECT_EQ(FolderLabel("/abs/eval"), "eval");
}

TEST(ReportTest, PolylineVerticesMapBackToTheCurve) {
  TestTempDir dir;
  EvaluateSmall(dir.path() / "eval", Matcher::kOptimal);
  const ReportSource source = ReadReportSource(dir.path() / "eval", "optimal");
  const std::vector<ReportFigure> figures = ReportFigures({source});
  const json& e = Entry(source.results, "Car", "2d", "Moderate");
  const Plot* pr = nullptr;
  for (const ReportFigure& f : figures) {
    if (f.plot.id == "pr_car_2d_moderate") pr = &f.plot;
  }
  ASSERT_NE(pr, nullptr);
  EXPECT_EQ(pr->series.size(), 1u);  // the optimal matcher has no 41-slot arrays
  const PlotFrame frame = LayOutPlot(*pr);
  const std::string svg = RenderSvg(*pr);
  const std::regex polyline("<polyline[^>]* points=\"([^\"]*)\"");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(svg, m, polyline));
  const std::string points = m[1];
  const std::regex pair("(-?[0-9.]+),(-?[0-9.]+)");
  size_t i = 0;
  const std::vector<double> recall = Column(e["curve"]["recall"]);
  const std::vector<double> precision = Column(e["curve"]["precision"]);
  // Drawn as steps: vertex 2k is the curve's point k, vertex 2k - 1 the corner (recall k,
  // precision k - 1) before it.
  for (std::sregex_iterator p(points.begin(), points.end(), pair), end; p != end; ++p, ++i) {
    ASSERT_LT(i, 2 * recall.size() - 1);
    const double x = frame.x_min + (std::stod((*p)[1]) - frame.left) / (frame.right - frame.left) *
                                       (frame.x_max - frame.x_min);
    const double y = frame.y_min + (frame.bottom - std::stod((*p)[2])) /
                                       (frame.bottom - frame.top) * (frame.y_max - frame.y_min);
    EXPECT_NEAR(x, recall[(i + 1) / 2], 0.01 / 400) << i;
    EXPECT_NEAR(y, precision[i / 2], 0.01 / 264) << i;
  }
  EXPECT_EQ(i, 2 * recall.size() - 1);
}

// The page holds every figure inline, its data as JSON, and nothing it would fetch.
TEST(ReportTest, PageIsSelfContainedAndHoldsEveryFigure) {
  TestTempDir dir;
  EvaluateSmall(dir.path() / "eval", Matcher::kKitti);
  const std::string html = ReadFile(dir.path() / "eval/report/index.html");
  std::set<std::string> svg_files;
  for (const auto& f : fs::directory_iterator(dir.path() / "eval/report/figures")) {
    if (f.path().extension() == ".svg") svg_files.insert(f.path().stem().string());
  }
  ASSERT_GT(svg_files.size(), 100u);
  for (const std::string& id : svg_files) {
    EXPECT_THAT(html, HasSubstr("<figure class=\"stereodet-figure\" id=\"fig-" + id + "\">"));
    EXPECT_THAT(html, HasSubstr("id=\"" + id + "\" class=\"plot\""));
  }
  const size_t begin = html.find("id=\"stereodet-figures\">") + 23;
  const json data = json::parse(html.substr(begin, html.find("</script>", begin) - begin));
  EXPECT_EQ(data.size(), svg_files.size());
  // A section's figures by kind, a row each (the difficulties of a kind side by side): the Car 2d
  // section in page order.
  std::vector<std::string> car_2d;
  const std::regex figure_or_row(
      "<div class=\"figures\" data-kind=\"([a-z_]+)\">|id=\"fig-([a-z_0-9]+_car_2d[a-z_]*)\"");
  for (std::sregex_iterator it(html.begin(), html.end(), figure_or_row), end; it != end; ++it) {
    if ((*it)[2].matched) car_2d.push_back((*it)[2]);
    if ((*it)[1].matched && !car_2d.empty() && car_2d.size() < 12) car_2d.push_back("|");
  }
  car_2d.resize(std::min<size_t>(car_2d.size(), 12));
  EXPECT_EQ(car_2d,
            (std::vector<std::string>{
                "pr_difficulties_car_2d", "|", "pr_car_2d_easy", "pr_car_2d_moderate",
                "pr_car_2d_hard", "|", "roc_car_2d_easy", "roc_car_2d_moderate", "roc_car_2d_hard",
                "|", "reliability_car_2d_easy", "reliability_car_2d_moderate"}));
  EXPECT_THAT(html, HasSubstr("figure.stereodet-figure svg{width:100%;height:auto}"));
  // Nothing to fetch: no src= attribute, no stylesheet link, no URL but the SVG namespace.
  EXPECT_THAT(html, Not(HasSubstr("src=")));
  EXPECT_THAT(html, Not(HasSubstr("<link")));
  std::string without_namespace = html;
  const std::string ns = "http://www.w3.org/2000/svg";
  for (size_t p; (p = without_namespace.find(ns)) != std::string::npos;) {
    without_namespace.erase(p, ns.size());
  }
  EXPECT_THAT(without_namespace, Not(HasSubstr("http")));
  EXPECT_THAT(html, HasSubstr("<table id=\"summary-table\">"));
}

// Two results folders: each series twice, one colour per folder, names in the legend.
TEST(ReportTest, SeveralResultsAreOverlaidOneColourEach) {
  TestTempDir dir;
  EvaluateSmall(dir.path() / "kitti", Matcher::kKitti);
  EvaluateSmall(dir.path() / "optimal", Matcher::kOptimal);
  ReportOptions options;
  options.results = {dir.path() / "kitti", dir.path() / "optimal"};
  options.out = dir.path() / "both";
  options.png = false;
  const ReportResult report = WriteReport(options);
  EXPECT_EQ(report.index, dir.path() / "both/index.html");
  const json pr = SvgData(dir.path() / "both/figures/pr_car_2d_moderate.svg");
  ASSERT_EQ(pr["series"].size(), 3u);  // kitti exact + devkit slots, optimal exact
  EXPECT_THAT(pr["series"][0]["name"].get<std::string>(), HasSubstr("kitti: kitti, exact curve"));
  EXPECT_THAT(pr["series"][2]["name"].get<std::string>(),
              HasSubstr("optimal: optimal, exact curve"));
  const std::string svg = ReadFile(dir.path() / "both/figures/pr_car_2d_moderate.svg");
  EXPECT_THAT(svg, HasSubstr("stroke=\"#0072B2\""));  // the first folder's colour
  EXPECT_THAT(svg, HasSubstr("stroke=\"#D55E00\""));  // the second's
  const std::string html = ReadFile(report.index);
  EXPECT_THAT(html, HasSubstr("<td class=\"t\">kitti</td>"));
  EXPECT_THAT(html, HasSubstr("<td class=\"t\">optimal</td>"));
  // The summary table holds a cell's folders together: kitti's row, then optimal's, cell by cell.
  const std::string table = html.substr(html.find("<table id=\"summary-table\">"));
  const std::regex row(
      "<tr><td class=\"t\">(kitti|optimal)</td><td class=\"t\">([A-Za-z]+)</td>"
      "<td class=\"t\">([a-z0-9]+)</td><td class=\"t\">([A-Za-z]+)</td>");
  std::vector<std::string> rows;
  for (std::sregex_iterator it(
           table.begin(), table.begin() + static_cast<std::ptrdiff_t>(table.find("</table>")), row),
       end;
       it != end; ++it) {
    rows.push_back((*it)[1].str() + " " + (*it)[2].str() + " " + (*it)[3].str() + " " +
                   (*it)[4].str());
  }
  ASSERT_GE(rows.size(), 4u);
  ASSERT_EQ(rows.size() % 2, 0u);
  for (size_t i = 0; i < rows.size(); i += 2) {
    EXPECT_EQ(rows[i].substr(0, 6), "kitti ") << rows[i];
    EXPECT_EQ("optimal" + rows[i].substr(5), rows[i + 1]);
  }
  // Brier: one colour per folder here too, the kinds of each difficulty as categories.
  const json brier = SvgData(dir.path() / "both/figures/brier_car_2d.svg");
  ASSERT_EQ(brier["series"].size(), 2u);
  EXPECT_EQ(brier["categories"].size(), 9u);
  EXPECT_EQ(brier["categories"][4], "M dets");
  const std::string brier_svg = ReadFile(dir.path() / "both/figures/brier_car_2d.svg");
  EXPECT_THAT(brier_svg, HasSubstr("fill=\"#0072B2\""));
  EXPECT_THAT(brier_svg, HasSubstr("fill=\"#D55E00\""));
  EXPECT_THAT(brier_svg, Not(HasSubstr("fill=\"#009E73\"")));
  // Difficulties by line: solid, dashed, dotted, in each folder's colour.
  const std::string by_difficulty =
      ReadFile(dir.path() / "both/figures/pr_difficulties_car_2d.svg");
  EXPECT_THAT(by_difficulty, HasSubstr("stroke-dasharray=\"5,3\""));
  EXPECT_THAT(by_difficulty, HasSubstr("stroke-dasharray=\"1.5,2.5\""));

  // Several folders need an out; a folder without results.json is refused with its name.
  ReportOptions no_out = options;
  no_out.out.clear();
  EXPECT_THROW(WriteReport(no_out), std::invalid_argument);
  ReportOptions not_results;
  not_results.results = {kData / "eval_small"};
  not_results.out = dir.path() / "never";
  try {
    WriteReport(not_results);
    ADD_FAILURE() << "no results.json, no report";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("eval_small/results.json is not there"));
  }
  EXPECT_FALSE(fs::exists(dir.path() / "never"));
}

// `eval compare` (tests/data/eval_compare, README): A errs +0.5 m / +1.0 m, B +0.2 m / -2.0 m at
// 12 m / 22 m, so A - B is +0.3 m in the 10-15 m bin and -1.0 m in the 20-25 m bin; the model's
// line is compare.csv's model_dz at every bin centre.
// The figure `id` of the report of one results folder.
Plot CompareFigurePlot(const fs::path& folder, const std::string& id) {
  for (const ReportFigure& f : ReportFigures({ReadReportSource(folder, "compare")})) {
    if (f.plot.id == id) return f.plot;
  }
  ADD_FAILURE() << "no figure " << id;
  return {};
}

// `eval compare --bootstrap --breakdown` folders: the page's difference table holds each cell's
// (and bin's) paired A - B of AP_R40 and Brier over labels as bootstrap.csv and
// bootstrap_breakdown.csv give them; without --bootstrap there is no table.
TEST(ReportTest, CompareReportHasThePairedDifferenceTable) {
  TestTempDir dir;
  EvaluationCompareOptions compare = CarCompareOptions();
  compare.out = dir.path() / "plain";
  RunEvaluationCompare(compare);
  ReportOptions options;
  options.results = {compare.out};
  options.png = false;
  WriteReport(options);
  EXPECT_THAT(ReadFile(compare.out / "report/index.html"),
              ::testing::Not(HasSubstr("paired-table")));

  compare.out = dir.path() / "paired";
  compare.bootstrap = BootstrapOptions{};
  compare.bootstrap->num_resamples = 30;
  compare.eval.breakdowns = {ParseBreakdown("distance=0,20,inf")};
  const EvaluationCompareResult result = RunEvaluationCompare(compare);
  options.results = {compare.out};
  WriteReport(options);
  const ReportSource source = ReadReportSource(compare.out, "paired");
  // bootstrap.csv: 3 difficulties x 5 measures; bootstrap_breakdown.csv: x 2 bins.
  EXPECT_EQ(source.paired.size(), 3u * 5u + 3u * 2u * 5u);
  const std::string html = ReadFile(compare.out / "report/index.html");
  EXPECT_THAT(html, HasSubstr("<table id=\"paired-table\">"));
  const BootstrapCell* moderate =
      result.bootstrap->difference.Find("Car", OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_NE(moderate, nullptr);
  const BootstrapInterval& ap = moderate->Get(BootstrapMetric::kApR40);
  EXPECT_THAT(html, HasSubstr("<td class=\"t\">Moderate</td><td class=\"t\">all</td>"
                              "<td class=\"t\">AP_R40</td>"));
  EXPECT_THAT(html,
              HasSubstr(fmt::format("{:.2f} [{:.2f}, {:.2f}]", ap.estimate, ap.lower, ap.upper)));
  EXPECT_THAT(html, HasSubstr("<td class=\"t\">distance [20, inf)</td>"));
}

TEST(ReportTest, CompareFigureShowsBothErrorsTheirDifferenceAndTheModel) {
  TestTempDir dir;
  EvaluationCompareOptions compare = CarCompareOptions();
  compare.out = dir.path() / "compare";
  RunEvaluationCompare(compare);
  ReportOptions options;
  options.results = {dir.path() / "compare"};
  options.png = false;
  const ReportResult report = WriteReport(options);
  EXPECT_EQ(report.num_figures, 3);  // Easy, Moderate, Hard
  const json fig = SvgData(dir.path() / "compare/report/figures/compare_car_2d_easy.svg");
  ASSERT_EQ(fig["series"].size(), 4u);
  EXPECT_EQ(fig["series"][2]["name"], "A - B");  // the sign issue 13 words the figure in
  const std::vector<double> x = Column(fig["series"][2]["x"]);
  const std::vector<double> diff = Column(fig["series"][2]["y"]);
  const auto at = [&](double centre) {
    return diff[static_cast<size_t>(std::find(x.begin(), x.end(), centre) - x.begin())];
  };
  EXPECT_NEAR(at(12.5), 0.3, 1e-9);
  EXPECT_NEAR(at(22.5), -1.0, 1e-9);
  EXPECT_TRUE(std::isnan(at(2.5)));                          // an empty bin: not drawn
  EXPECT_NEAR(Column(fig["series"][0]["y"])[2], 0.5, 1e-9);  // A at 10-15 m
  EXPECT_NEAR(Column(fig["series"][1]["y"])[4], 2.0, 1e-9);  // |B| at 20-25 m
  auto csv = ReadCsv(dir.path() / "compare/compare.csv");
  std::vector<double> model = Column(fig["series"][3]["y"]);
  ASSERT_LE(model.size(), csv["model_dz"].size());
  csv["model_dz"].resize(model.size());  // the Easy rows come first
  EXPECT_TRUE(SameNumbers(model, csv["model_dz"]));
  // The legends name the two detection folders (compare.json), the axis is scaled to the
  // measured errors (|B| 2.0 m at most, A - B -1.0 m at least) and the caption counts the pairs of
  // each bin.
  EXPECT_EQ(fig["series"][0]["name"], "A (det_a): mean |depth error|");
  EXPECT_EQ(fig["series"][1]["name"], "B (det_b): mean |depth error|");
  const std::string html = ReadFile(report.index);
  EXPECT_THAT(html, HasSubstr("per bin, A/B: 10-15 m: 1/1, 20-25 m: 1/1"));
  std::vector<double> measured;
  for (int k = 0; k < 3; ++k) {
    for (double v : Column(fig["series"][k]["y"])) {
      if (std::isfinite(v)) measured.push_back(v);
    }
  }
  const double top = *std::max_element(measured.begin(), measured.end());
  EXPECT_EQ(top, 2.0);
  const PlotFrame frame =
      LayOutPlot(CompareFigurePlot(dir.path() / "compare", "compare_car_2d_easy"));
  EXPECT_GE(frame.y_max, 2.5);
  EXPECT_LT(frame.y_max, 4.0);  // not the model's z^2 growth (12 m at 77.5 m)
  EXPECT_LE(frame.y_min, -1.25);
}

// With several results folders the page has the paper's Table 1: per class a table, one row per
// folder, at Car / Pedestrian / Cyclist Moderate 2D (first overlap set): AP_R40, AP_R11, the exact
// AP and the Brier score over labels, each as results.json has it.
TEST(ReportTest, SeveralResultsGetTable1OneRowPerModelPerClass) {
  TestTempDir dir;
  EvaluateSmall(dir.path() / "kitti", Matcher::kKitti);
  EvaluateSmall(dir.path() / "optimal", Matcher::kOptimal);
  ReportOptions options;
  options.results = {dir.path() / "kitti", dir.path() / "optimal"};
  options.out = dir.path() / "both";
  options.png = false;
  const std::string html = ReadFile(WriteReport(options).index);
  for (const std::string class_name : {"Car", "Pedestrian", "Cyclist"}) {
    std::string lower = class_name;
    for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const size_t start = html.find("<table class=\"table1\" id=\"table1-" + lower + "\">");
    ASSERT_NE(start, std::string::npos) << class_name;
    const std::string table = html.substr(start, html.find("</table>", start) - start);
    std::vector<std::string> expected_rows;
    for (const char* name : {"kitti", "optimal"}) {
      const json results = json::parse(ReadFile(dir.path() / name / "results.json"));
      for (const json& e : results["results"]) {
        if (e["class"] != class_name || e["metric"] != "2d" || e["difficulty"] != "Moderate") {
          continue;
        }
        auto fixed = [&](const json& v, int decimals) {
          return v.is_number() && std::isfinite(v.get<double>())
                     ? fmt::format("{:.{}f}", v.get<double>(), decimals)
                     : std::string("-");
        };
        expected_rows.push_back(fmt::format(
            "<tr><td class=\"t\">{}</td><td class=\"t\">{}</td><td>{}{}</td><td>{}</td>"
            "<td>{}</td><td>{}</td><td>{}</td></tr>",
            name, name, e["num_valid_labels"].get<int>(), e.value("small_sample", false) ? "*" : "",
            fixed(e["ap_r40"], 2), fixed(e["ap_r11"], 2), fixed(e["ap_voc"], 2),
            fixed(e["brier"]["over_labels"], 4)));
      }
    }
    ASSERT_EQ(expected_rows.size(), 2u) << class_name;
    for (const std::string& row : expected_rows) EXPECT_THAT(table, HasSubstr(row)) << class_name;
    EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 4) << table;  // header, 2 rows
  }
  // (The KITTI matcher computes no exact AP: its rows expect "-" there, from ap_voc null.)
  EXPECT_THAT(html, HasSubstr("Table 1: one row per model"));
  // One folder: no Table 1.
  ReportOptions one = options;
  one.results = {dir.path() / "kitti"};
  one.out = dir.path() / "one";
  EXPECT_THAT(ReadFile(WriteReport(one).index), Not(HasSubstr("table1")));
}

// compare.csv also says A - B (the sign issue 13 words): the negative of B - A in every row, +0.3 m
// in the 10-15 m bin (A errs 0.5 m, B 0.2 m), appended after the earlier columns.
TEST(ReportTest, CompareCsvHasTheDifferenceAMinusBAsItsLastColumn) {
  TestTempDir dir;
  EvaluationCompareOptions compare = CarCompareOptions();
  compare.out = dir.path() / "compare";
  RunEvaluationCompare(compare);
  const std::string text = ReadFile(dir.path() / "compare/compare.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "class,metric,difficulty,lower_m,upper_m,count_a,abs_dz_mean_a,count_b,abs_dz_mean_b,"
            "difference_b_minus_a,centre_error_mean_a,centre_error_mean_b,model_dz,"
            "difference_a_minus_b");
  auto csv = ReadCsv(dir.path() / "compare/compare.csv");
  const std::vector<double>& b_minus_a = csv["difference_b_minus_a"];
  const std::vector<double>& a_minus_b = csv["difference_a_minus_b"];
  ASSERT_EQ(a_minus_b.size(), b_minus_a.size());
  int compared = 0;
  for (size_t i = 0; i < a_minus_b.size(); ++i) {
    EXPECT_EQ(std::isnan(a_minus_b[i]), std::isnan(b_minus_a[i])) << i;
    if (std::isnan(a_minus_b[i])) continue;
    EXPECT_NEAR(a_minus_b[i], -b_minus_a[i], 1e-12) << i;
    ++compared;
  }
  EXPECT_GE(compared, 2);
  const std::vector<double>& lower = csv["lower_m"];
  const size_t near =
      static_cast<size_t>(std::find(lower.begin(), lower.end(), 10.0) - lower.begin());
  ASSERT_LT(near, lower.size());
  EXPECT_NEAR(a_minus_b[near], 0.3, 1e-9);
}

// `eval sweep`: the naive and the stable precision and recall of sweep.csv against the value.
TEST(ReportTest, SweepFigurePlotsSweepCsv) {
  TestTempDir dir;
  EvaluationSweepOptions sweep;
  sweep.input.gt = kData / "eval_small";
  sweep.input.det = kData / "eval_small/det";
  sweep.eval.classes = {KittiClassSpec("Car")};
  sweep.eval.metrics = {OverlapKind::k2D};
  sweep.from = 0, sweep.to = 2000, sweep.step = 250;
  sweep.out = dir.path() / "sweep";
  const EvaluationSweepResult result = RunEvaluationSweep(sweep);
  ReportOptions options;
  options.results = {dir.path() / "sweep"};
  options.png = false;
  EXPECT_EQ(WriteReport(options).num_figures, 3);
  const json fig = SvgData(dir.path() / "sweep/report/figures/sweep_car_2d_moderate.svg");
  ASSERT_EQ(fig["series"].size(), 4u);
  std::vector<double> value, naive_p, stable_p, naive_r, stable_r;
  for (const SweepRow& row : result.rows) {
    if (row.difficulty != Difficulty::kModerate) continue;
    value.push_back(row.value);
    naive_p.push_back(row.stats.naive.precision);
    stable_p.push_back(row.stats.stable.precision);
    naive_r.push_back(row.stats.naive.recall);
    stable_r.push_back(row.stats.stable.recall);
  }
  ASSERT_EQ(value.size(), 9u);  // 0, 250, ..., 2000
  EXPECT_TRUE(SameNumbers(Column(fig["series"][0]["x"]), value));
  EXPECT_TRUE(SameNumbers(Column(fig["series"][0]["y"]), naive_p));
  EXPECT_TRUE(SameNumbers(Column(fig["series"][1]["y"]), stable_p));
  EXPECT_TRUE(SameNumbers(Column(fig["series"][2]["y"]), naive_r));
  EXPECT_TRUE(SameNumbers(Column(fig["series"][3]["y"]), stable_r));

  // A sweep and an evaluation do not mix in one report.
  EvaluateSmall(dir.path() / "eval", Matcher::kKitti);
  ReportOptions mixed;
  mixed.results = {dir.path() / "eval", dir.path() / "sweep"};
  mixed.out = dir.path() / "mixed";
  EXPECT_THROW(WriteReport(mixed), std::invalid_argument);
}

TEST(ReportTest, PngFilesAreTheSvgRasterizedAtTwiceTheSize) {
  if (!PngFromSvgAvailable()) GTEST_SKIP() << "built without librsvg: no PNG output";
  TestTempDir dir;
  EvaluateSmall(dir.path() / "eval", Matcher::kKitti, /*png=*/true, /*car_2d_only=*/true);
  const std::string png = ReadFile(dir.path() / "eval/report/figures/pr_car_2d_moderate.png");
  ASSERT_GT(png.size(), 24u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  auto be32 = [&](size_t at) {
    return (static_cast<uint32_t>(static_cast<unsigned char>(png[at])) << 24) |
           (static_cast<uint32_t>(static_cast<unsigned char>(png[at + 1])) << 16) |
           (static_cast<uint32_t>(static_cast<unsigned char>(png[at + 2])) << 8) |
           static_cast<uint32_t>(static_cast<unsigned char>(png[at + 3]));
  };
  EXPECT_EQ(be32(16), 960u);  // IHDR width: 2 x 480 px
  // Height: 2 x (340 px + two legend rows of 17 px + 6).
  EXPECT_EQ(be32(20), 2u * (340 + 2 * 17 + 6));
  EXPECT_THROW(WritePngFromSvg(dir.path() / "bad.png", "not svg"), std::runtime_error);
  EXPECT_FALSE(fs::exists(dir.path() / "bad.png"));
}

// A figure overlaying many models (the experiment's 15) embeds more than 10 MB of curve data in
// one <metadata> CDATA section: over libxml2's default limit, which librsvg's plain loader keeps.
TEST(ReportTest, PngOfAnSvgWithMoreThanTenMegabytesOfMetadata) {
  if (!PngFromSvgAvailable()) GTEST_SKIP() << "built without librsvg: no PNG output";
  const std::string svg =
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"4\" height=\"2\">\n<metadata><![CDATA[" +
      std::string(11'000'000, '7') +
      "]]></metadata>\n<rect x=\"2\" y=\"0\" width=\"2\" height=\"2\" fill=\"#ff0000\"/></svg>";
  const RasterImage image = RasterizeSvg(svg);
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 2);
  EXPECT_EQ(image.At(0, 0), 0xffffffu);  // the white background
  EXPECT_EQ(image.At(3, 1), 0xff0000u);  // the rectangle
}

}  // namespace
}  // namespace stereodet
