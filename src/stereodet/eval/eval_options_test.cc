#include "stereodet/eval/eval_options.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>

namespace stereodet {
namespace {

TEST(EvalOptionsTest, CompatNamesRoundTrip) {
  for (EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    EXPECT_EQ(ParseEvalCompat(EvalCompatName(c)), c);
  }
  EXPECT_EQ(ParseEvalCompat("OpenPCDet"), EvalCompat::kOpenPcdet);
  EXPECT_FALSE(ParseEvalCompat("mmdet").has_value());
}

TEST(EvalOptionsTest, OpenPcdetCompatNeedsTheKittiMatcher) {
  EvalOptions options;
  options.compat = EvalCompat::kOpenPcdet;
  EXPECT_NO_THROW(options.Check());
  options.matcher = Matcher::kOptimal;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

// Option checks name the field and its value (the comparison checks of util/check.h).
TEST(EvalOptionsTest, CheckMessagesNameTheFieldAndItsValue) {
  auto message = [](const EvalOptions& o) -> std::string {
    try {
      o.Check();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EvalOptions o;
  o.num_threads = -2;
  EXPECT_NE(message(o).find("num_threads = -2, must be >= 0"), std::string::npos) << message(o);
  o = EvalOptions();
  o.distance_bin_m = -5;
  EXPECT_NE(message(o).find("distance_bin_m must be a finite number > 0, got -5"),
            std::string::npos)
      << message(o);
  for (const double bad :
       {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    o.distance_bin_m = bad;
    EXPECT_NE(message(o).find("distance_bin_m must be a finite number > 0"), std::string::npos)
        << message(o);
  }
  o = EvalOptions();
  o.distance_bin_m = 1e-4;
  EXPECT_NE(message(o).find("must be <= 100000 (localization bins)"), std::string::npos)
      << message(o);
}

// Every enum of the options: Name() then Parse() gives the value back, a bad name gives nullopt.

TEST(EvalOptionsTest, MatcherNamesRoundTrip) {
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EXPECT_EQ(ParseMatcher(MatcherName(m)), m) << MatcherName(m);
  }
  EXPECT_STREQ(MatcherName(Matcher::kOptimal), "optimal");
  EXPECT_EQ(ParseMatcher("hungarian"), std::nullopt);
  EXPECT_EQ(ParseMatcher(""), std::nullopt);
}

TEST(EvalOptionsTest, EvalCompatNamesRoundTrip) {
  for (EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    EXPECT_EQ(ParseEvalCompat(EvalCompatName(c)), c) << EvalCompatName(c);
  }
  EXPECT_EQ(ParseEvalCompat("mmdet3d"), std::nullopt);
}

TEST(EvalOptionsTest, OverlapKindNamesRoundTrip) {
  for (OverlapKind k : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
    EXPECT_EQ(ParseOverlapKind(OverlapKindName(k)), k) << OverlapKindName(k);
  }
  EXPECT_EQ(ParseOverlapKind("BEV"), OverlapKind::kBev);  // case-insensitive, as --metrics
  EXPECT_EQ(ParseOverlapKind("4d"), std::nullopt);
}

TEST(EvalOptionsTest, OverlapSetNamesRoundTrip) {
  for (OverlapSet s : {OverlapSet::kStrict, OverlapSet::kLoose}) {
    EXPECT_EQ(ParseOverlapSet(OverlapSetName(s)), s) << OverlapSetName(s);
  }
  EXPECT_EQ(ParseOverlapSet("custom"), std::nullopt);
}

TEST(EvalOptionsTest, ScoreTransformNamesRoundTrip) {
  for (ScoreTransform t : {ScoreTransform::kNone, ScoreTransform::kSigmoid}) {
    EXPECT_EQ(ParseScoreTransform(ScoreTransformName(t)), t) << ScoreTransformName(t);
  }
  EXPECT_EQ(ParseScoreTransform("logit"), std::nullopt);
}

}  // namespace
}  // namespace stereodet
