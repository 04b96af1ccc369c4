#include "stereodet/kitti/score_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

ScoreCalibration CarAndPedestrian() {
  ScoreCalibration c;
  ScoreCalibrator temperature;
  temperature.method = CalibrationMethod::kTemperature;
  temperature.slope = 0.5;  // T = 2
  ScoreCalibrator isotonic;
  isotonic.method = CalibrationMethod::kIsotonic;
  isotonic.x = {0.2, 0.4, 0.8};
  isotonic.y = {0.1, 0.5, 0.9};
  c.classes = {{"Car", temperature}, {"Pedestrian", isotonic}};
  c.fitted_on = {{"frames", "500"}, {"matcher", "optimal"}};
  return c;
}

// By hand: a score of 0.8 has logit log 4; at T = 2, sigmoid(log 2) = 2/3. Platt with slope 2 and
// intercept -log 2 maps logit 0 (score 0.5) to sigmoid(-log 2) = 1/3. Isotonic: linear between its
// points, clamped outside.
TEST(ScoreCalibrationTest, MapsByHand) {
  const ScoreCalibration c = CarAndPedestrian();
  const ScoreCalibrator& t = c.classes[0].second;
  EXPECT_NEAR(t.Apply(0.8, false), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(t.Apply(std::log(4.0), true), 2.0 / 3.0, 1e-12);  // a logit score
  EXPECT_NEAR(t.Apply(0.5, false), 0.5, 1e-12);
  ScoreCalibrator platt;
  platt.method = CalibrationMethod::kPlatt;
  platt.slope = 2;
  platt.intercept = -std::log(2.0);
  EXPECT_NEAR(platt.Apply(0.5, false), 1.0 / 3.0, 1e-12);
  // Scores of exactly 0 and 1 are clamped before their logit: finite, ordered.
  EXPECT_GT(t.Apply(1.0, false), t.Apply(0.999, false));
  EXPECT_GT(t.Apply(0.0, false), 0.0);
  const ScoreCalibrator& iso = c.classes[1].second;
  EXPECT_EQ(iso.Apply(0.0, false), 0.1);
  EXPECT_EQ(iso.Apply(0.2, false), 0.1);
  EXPECT_NEAR(iso.Apply(0.3, false), 0.3, 1e-12);
  EXPECT_NEAR(iso.Apply(0.6, false), 0.7, 1e-12);
  EXPECT_EQ(iso.Apply(0.8, false), 0.9);
  EXPECT_EQ(iso.Apply(5.0, false), 0.9);
}

TEST(ScoreCalibrationTest, AppliesToItsClassesOnly) {
  const ScoreCalibration c = CarAndPedestrian();
  Object car, van, ped;
  car.type = "car";  // any case, as the evaluator's names
  car.score = 0.8;
  van.type = "Van";
  van.score = 0.8;
  ped.type = "Pedestrian";
  ped.score = 0.3;
  std::vector<Object> dets = {car, van, ped};
  EXPECT_EQ(c.Apply(&dets), 2);
  EXPECT_NEAR(*dets[0].score, 2.0 / 3.0, 1e-12);
  EXPECT_EQ(*dets[1].score, 0.8);
  EXPECT_NEAR(*dets[2].score, 0.3, 1e-12);
  std::vector<Object> no_score = {car};
  no_score[0].score.reset();
  EXPECT_THROW(c.Apply(&no_score), std::invalid_argument);
}

TEST(ScoreCalibrationTest, FileRoundTripsAndBadFilesNameTheField) {
  const ScoreCalibration c = CarAndPedestrian();
  const std::string text = ScoreCalibrationToJson(c);
  const ScoreCalibration back = ParseScoreCalibration(text, "calib.json");
  ASSERT_EQ(back.classes.size(), 2u);
  EXPECT_EQ(back.classes[0].first, "Car");
  EXPECT_EQ(back.classes[0].second.slope, 0.5);
  EXPECT_EQ(back.classes[1].second.x, c.classes[1].second.x);
  EXPECT_EQ(back.classes[1].second.y, c.classes[1].second.y);
  EXPECT_EQ(back.fitted_on, c.fitted_on);
  EXPECT_EQ(ScoreCalibrationToJson(back), text);

  auto error = [](const std::string& text) {
    try {
      ParseScoreCalibration(text, "calib.json");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("{").find("calib.json: not JSON"), std::string::npos);
  EXPECT_NE(error(R"({"format": "x"})").find("not a stereodet score calibration"),
            std::string::npos);
  const std::string head =
      R"({"format": "stereodet score calibration", "version": 1, "scores_are_logits": false, )";
  EXPECT_NE(error(head + R"("classes": [{"class": "Car", "method": "platt", "slope": 1}]})")
                .find("calib.json: classes[0].intercept is missing"),
            std::string::npos);
  EXPECT_NE(error(head + R"("classes": [{"class": "Car", "method": "beta"}]})")
                .find("classes[0].method must be temperature, platt or isotonic"),
            std::string::npos);
  EXPECT_NE(error(head + R"("classes": [{"class": "Car", "method": "platt", "slope": -1, )"
                         R"("intercept": 0}]})")
                .find("class 'Car': platt: the slope must be finite and > 0"),
            std::string::npos);
  EXPECT_NE(error(head + R"("classes": [{"class": "Car", "method": "isotonic", "x": [0.1, 0.2], )"
                         R"("y": [0.5, 0.4]}]})")
                .find("y must not decrease"),
            std::string::npos);
  EXPECT_NE(error(head + R"("classes": []})").find("no class"), std::string::npos);
  EXPECT_NE(error(R"({"format": "stereodet score calibration", "version": 2})").find("version 2"),
            std::string::npos);
}

}  // namespace
}  // namespace stereodet
