#include "stereodet/eval/eval_options.h"

#include <gtest/gtest.h>

namespace stereodet {
namespace {

// Every enum of the options: Name() then Parse() gives the value back, a bad name gives nullopt.

TEST(EvalOptionsNamesTest, Matcher) {
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EXPECT_EQ(ParseMatcher(MatcherName(m)), m) << MatcherName(m);
  }
  EXPECT_STREQ(MatcherName(Matcher::kOptimal), "optimal");
  EXPECT_EQ(ParseMatcher("hungarian"), std::nullopt);
  EXPECT_EQ(ParseMatcher(""), std::nullopt);
}

TEST(EvalOptionsNamesTest, EvalCompat) {
  for (EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    EXPECT_EQ(ParseEvalCompat(EvalCompatName(c)), c) << EvalCompatName(c);
  }
  EXPECT_EQ(ParseEvalCompat("mmdet3d"), std::nullopt);
}

TEST(EvalOptionsNamesTest, OverlapKind) {
  for (OverlapKind k : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
    EXPECT_EQ(ParseOverlapKind(OverlapKindName(k)), k) << OverlapKindName(k);
  }
  EXPECT_EQ(ParseOverlapKind("BEV"), OverlapKind::kBev);  // case-insensitive, as --metrics
  EXPECT_EQ(ParseOverlapKind("4d"), std::nullopt);
}

TEST(EvalOptionsNamesTest, OverlapSet) {
  for (OverlapSet s : {OverlapSet::kStrict, OverlapSet::kLoose}) {
    EXPECT_EQ(ParseOverlapSet(OverlapSetName(s)), s) << OverlapSetName(s);
  }
  EXPECT_EQ(ParseOverlapSet("custom"), std::nullopt);
}

TEST(EvalOptionsNamesTest, ScoreTransform) {
  for (ScoreTransform t : {ScoreTransform::kNone, ScoreTransform::kSigmoid}) {
    EXPECT_EQ(ParseScoreTransform(ScoreTransformName(t)), t) << ScoreTransformName(t);
  }
  EXPECT_EQ(ParseScoreTransform("logit"), std::nullopt);
}

}  // namespace
}  // namespace stereodet
