#include "stereodet/eval/compare.h"

#include <gtest/gtest.h>

#include <cmath>

namespace stereodet {
namespace {

Object Car(double left, double z, double dz = 0.0, double score = -1) {
  Object o;
  o.type = "Car";
  o.box = {left, 150, left + 100, 250};  // 100 px high: Easy
  o.box3d.h = 1.5;
  o.box3d.w = 1.6;
  o.box3d.l = 3.9;
  o.box3d.location = {0.0, 1.7, z + dz};
  if (score >= 0) o.score = score;
  return o;
}

// Two labels, at 12 m (bin 10-15) and 22 m (bin 20-25). A errs by +0.5 m and +1.0 m in depth, B by
// +0.2 m and -2.0 m; the 2D boxes are exact, so all four pairs match in 2D. Per bin: mean |dz| A
// 0.5 and 1.0, B 0.2 and 2.0, B - A = -0.3 and +1.0; the centre error is |dz| (only z differs); the
// model is z^2 / (b f) * dd at the bin centre (12.5 m and 22.5 m).
TEST(CompareTest, LocalizationOfTwoDetectionSetsByHand) {
  EvalFrame fa, fb;
  fa.labels = fb.labels = {Car(100, 12), Car(600, 22)};
  fa.detections = {Car(100, 12, 0.5, 0.9), Car(600, 22, 1.0, 0.8)};
  fb.detections = {Car(100, 12, 0.2, 0.9), Car(600, 22, -2.0, 0.8)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kEasy};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult a = Evaluate({fa}, options);
    const EvalResult b = Evaluate({fb}, options);
    CompareOptions co;
    co.baseline_m = 0.5;
    co.focal_px = 700;
    co.disparity_error_px = 2;
    const std::vector<CompareRow> rows = CompareLocalization(a, b, co);
    ASSERT_EQ(rows.size(), 16u);  // 80 m / 5 m bins
    const CompareRow& near = rows[2];
    const CompareRow& far = rows[4];
    EXPECT_EQ(near.lower_m, 10.0);
    EXPECT_EQ(far.upper_m, 25.0);
    EXPECT_EQ(near.count_a, 1);
    EXPECT_EQ(far.count_b, 1);
    EXPECT_NEAR(near.abs_depth_error_mean_a_m, 0.5, 1e-12);
    EXPECT_NEAR(near.abs_depth_error_mean_b_m, 0.2, 1e-12);
    EXPECT_NEAR(near.difference_b_minus_a_m, -0.3, 1e-12) << MatcherName(m);
    EXPECT_NEAR(far.difference_b_minus_a_m, 1.0, 1e-12) << MatcherName(m);
    EXPECT_NEAR(far.centre_error_mean_b_m, 2.0, 1e-12);
    EXPECT_NEAR(near.model_depth_error_m, 12.5 * 12.5 / (0.5 * 700) * 2, 1e-12);
    EXPECT_NEAR(far.model_depth_error_m, 22.5 * 22.5 / (0.5 * 700) * 2, 1e-12);
    EXPECT_EQ(rows[0].count_a, 0);
    EXPECT_TRUE(std::isnan(rows[0].difference_b_minus_a_m));
  }
  CompareOptions bad;
  bad.baseline_m = 0;
  const EvalResult a = Evaluate({fa}, options);
  EXPECT_THROW(CompareLocalization(a, a, bad), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
