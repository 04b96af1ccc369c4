#include "stereodet/eval/calibration_fit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

std::vector<double> Logits(const std::vector<double>& scores) {
  std::vector<double> x;
  for (double s : scores) x.push_back(std::log(s / (1 - s)));
  return x;
}

// Isotonic by hand: targets 0, 1, 0, 1 at ascending scores pool the middle two: 0, 0.5, 0.5, 1.
// Equal scores are one point first (their mean). Points inside a constant run are dropped.
TEST(CalibrationFitTest, IsotonicByHand) {
  ScoreCalibrator c = FitIsotonic({0.1, 0.2, 0.3, 0.4}, {0, 1, 0, 1});
  EXPECT_EQ(c.x, (std::vector<double>{0.1, 0.2, 0.3, 0.4}));
  EXPECT_EQ(c.y, (std::vector<double>{0.0, 0.5, 0.5, 1.0}));
  EXPECT_EQ(c.Apply(0.25, false), 0.5);
  EXPECT_NEAR(c.Apply(0.35, false), 0.75, 1e-12);
  c = FitIsotonic({0.5, 0.1, 0.5, 0.2, 0.3, 0.9}, {1, 0, 0, 0, 0, 1});
  EXPECT_EQ(c.x, (std::vector<double>{0.1, 0.3, 0.5, 0.9}));  // 0.2 inside the run of zeros
  EXPECT_EQ(c.y, (std::vector<double>{0.0, 0.0, 0.5, 1.0}));
  EXPECT_NO_THROW(c.Check());
}

// Temperature and Platt are where their gradients vanish: the negative log likelihood's gradient
// in the slope (temperature), and in slope and intercept against Platt's smoothed targets.
TEST(CalibrationFitTest, TemperatureAndPlattSitAtTheirOptimum) {
  const std::vector<double> scores = {0.9, 0.8, 0.75, 0.6, 0.55, 0.4, 0.3, 0.2, 0.95, 0.7};
  const std::vector<uint8_t> targets = {1, 1, 0, 1, 0, 0, 1, 0, 1, 0};
  const std::vector<double> x = Logits(scores);
  const ScoreCalibrator t = FitTemperature(x, targets);
  double g = 0;
  for (size_t i = 0; i < x.size(); ++i) g += (t.Apply(x[i], true) - targets[i]) * x[i];
  EXPECT_NEAR(g, 0.0, 1e-9);
  EXPECT_EQ(t.intercept, 0.0);
  const ScoreCalibrator p = FitPlatt(x, targets);
  const double hi = (5.0 + 1) / (5 + 2), lo = 1.0 / (5 + 2);
  double ga = 0, gb = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double r = p.Apply(x[i], true) - (targets[i] ? hi : lo);
    ga += r * x[i];
    gb += r;
  }
  EXPECT_NEAR(ga, 0.0, 1e-9);
  EXPECT_NEAR(gb, 0.0, 1e-9);
  // Scores that rank the false positives first cannot be calibrated by an order-keeping map.
  std::vector<uint8_t> reversed(targets.size());
  for (size_t i = 0; i < x.size(); ++i) reversed[i] = scores[i] < 0.6 ? 1 : 0;
  EXPECT_THROW(FitTemperature(x, reversed), std::invalid_argument);
  EXPECT_THROW(FitPlatt(x, reversed), std::invalid_argument);
}

// scikit-learn's and SciPy's fits on six sets of 40 to 3000 pairs (tests/data/calibration,
// scripts/calibration_reference_cases.py): the same probability at every probe score. Isotonic is
// exact; Platt's reference stops where BFGS does (scikit-learn's default gradient tolerance), so
// 1e-4; temperature's bounded search to 1e-10 in the slope.
TEST(CalibrationFitTest, AgreesWithScikitLearn) {
  const auto dir = TestSourceDir() / "tests/data/calibration";
  std::map<int, std::pair<std::vector<double>, std::vector<uint8_t>>> cases;
  std::ifstream points(dir / "points.csv");
  ASSERT_TRUE(points) << dir / "points.csv";
  std::string line;
  std::getline(points, line);
  while (std::getline(points, line)) {
    std::stringstream in(line);
    std::string c, s, t;
    std::getline(in, c, ',');
    std::getline(in, s, ',');
    std::getline(in, t, ',');
    cases[std::stoi(c)].first.push_back(std::stod(s));
    cases[std::stoi(c)].second.push_back(static_cast<uint8_t>(std::stoi(t)));
  }
  ASSERT_EQ(cases.size(), 6u);
  std::map<int, std::map<std::string, ScoreCalibrator>> fits;
  for (const auto& [k, data] : cases) {
    fits[k]["isotonic"] = FitIsotonic(data.first, data.second);
    fits[k]["platt"] = FitPlatt(Logits(data.first), data.second);
    fits[k]["temperature"] = FitTemperature(Logits(data.first), data.second);
  }
  std::ifstream expected(dir / "expected.csv");
  std::getline(expected, line);
  std::map<std::string, int> checked;
  while (std::getline(expected, line)) {
    std::stringstream in(line);
    std::string c, method, probe, p;
    std::getline(in, c, ',');
    std::getline(in, method, ',');
    std::getline(in, probe, ',');
    std::getline(in, p, ',');
    const double score = std::stod(probe), want = std::stod(p);
    const ScoreCalibrator& fit = fits.at(std::stoi(c)).at(method);
    const double tolerance = method == "isotonic" ? 1e-12 : method == "platt" ? 1e-4 : 1e-7;
    EXPECT_NEAR(fit.Apply(score, false), want, tolerance)
        << "case " << c << " " << method << " at " << probe;
    ++checked[method];
  }
  EXPECT_EQ(checked.size(), 3u);
  EXPECT_GT(checked["isotonic"], 500);
}

// On random frames: the targets are the matcher's TPs and FPs at every score (the cell's counts
// at the lowest threshold); in-sample, isotonic never raises the Brier score (the identity is one
// of the maps it minimises over) and temperature never raises the log loss (T = 1 is one of its).
TEST(CalibrationFitTest, FitsOnTheMatchersTargets) {
  RandomFramesOptions ro;
  ro.num_frames = 300;
  ro.seed = 37;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  CalibrationFitOptions options;
  options.eval.classes = {KittiClassSpec("Car"), KittiClassSpec("Pedestrian")};
  const EvalResult result = Evaluate(frames, options.eval);
  for (const CalibrationMethod method :
       {CalibrationMethod::kIsotonic, CalibrationMethod::kTemperature, CalibrationMethod::kPlatt}) {
    SCOPED_TRACE(CalibrationMethodName(method));
    options.method = method;
    const CalibrationFit fit = FitScoreCalibration(frames, options);
    ASSERT_EQ(fit.classes.size(), 2u);
    for (const ClassCalibrationFit& c : fit.classes) {
      const ClassResult* cell = result.Find(c.class_name, OverlapKind::k2D, Difficulty::kModerate);
      ASSERT_NE(cell, nullptr);
      EXPECT_EQ(c.num_tp, cell->at_threshold.tp);
      EXPECT_EQ(c.num_fp, cell->at_threshold.fp);
      if (method == CalibrationMethod::kIsotonic) {
        EXPECT_LE(c.brier_after, c.brier_before + 1e-12);
      }
      if (method == CalibrationMethod::kTemperature) {
        EXPECT_LE(c.nll_after, c.nll_before + 1e-12);
      }
    }
    EXPECT_NO_THROW(fit.calibration.Check());
    EXPECT_EQ(fit.calibration.classes.at(0).second.method, method);
  }
  // A class with no false positive has nothing to fit.
  for (EvalFrame& f : frames) {
    std::vector<Object> kept;
    for (const Object& l : f.labels) {
      if (l.type != "Car") continue;
      Object d = l;
      d.score = 0.9;
      kept.push_back(d);
    }
    f.detections = kept;
  }
  options.eval.classes = {KittiClassSpec("Car")};
  EXPECT_THROW(FitScoreCalibration(frames, options), std::invalid_argument);
  // With skip_unfittable the class is listed with why (and Pedestrian, with no detection left, as
  // well); the file round-trips, and applying it changes no score.
  options.skip_unfittable = true;
  options.eval.classes = {KittiClassSpec("Car"), KittiClassSpec("Pedestrian")};
  const CalibrationFit unfitted = FitScoreCalibration(frames, options);
  EXPECT_TRUE(unfitted.calibration.classes.empty());
  ASSERT_EQ(unfitted.calibration.unfitted.size(), 2u);
  EXPECT_EQ(unfitted.calibration.unfitted[0].first, "Car");
  EXPECT_THAT(unfitted.calibration.unfitted[0].second,
              ::testing::HasSubstr("0 false positives in 2d at Moderate"));
  EXPECT_EQ(unfitted.calibration.unfitted[1].first, "Pedestrian");
  EXPECT_THAT(unfitted.calibration.unfitted[1].second, ::testing::HasSubstr("no detection"));
  ASSERT_EQ(unfitted.classes.size(), 2u);
  EXPECT_FALSE(unfitted.classes[0].fitted);
  EXPECT_GT(unfitted.classes[0].num_tp, 0);
  const ScoreCalibration back =
      ParseScoreCalibration(ScoreCalibrationToJson(unfitted.calibration), "round trip");
  EXPECT_EQ(back.unfitted, unfitted.calibration.unfitted);
  std::vector<Object> detections = frames.front().detections;
  EXPECT_EQ(back.Apply(&detections), 0);
  options.eval.metrics = {OverlapKind::k2D, OverlapKind::k3D};
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
