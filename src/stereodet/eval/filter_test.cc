#include "stereodet/eval/filter.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace stereodet {
namespace {

TEST(FilterNamesTest, FilterModeRoundTrip) {
  for (FilterMode m : {FilterMode::kNaive, FilterMode::kStable}) {
    EXPECT_EQ(ParseFilterMode(FilterModeName(m)), m) << FilterModeName(m);
  }
  EXPECT_EQ(ParseFilterMode("strict"), std::nullopt);
}

TEST(FilterNamesTest, FilterBoundRoundTrip) {
  const FilterBound all[] = {
      FilterBound::kMinHeight,     FilterBound::kMaxHeight,   FilterBound::kMinWidth,
      FilterBound::kMaxWidth,      FilterBound::kMinArea,     FilterBound::kMaxArea,
      FilterBound::kMinDistance,   FilterBound::kMaxDistance, FilterBound::kMaxOcclusion,
      FilterBound::kMaxTruncation, FilterBound::kDifficulty,
  };
  for (FilterBound b : all) {
    EXPECT_EQ(ParseFilterBound(FilterBoundName(b)), b) << FilterBoundName(b);
    EXPECT_STRNE(FilterBoundName(b), "?");
  }
  EXPECT_STREQ(FilterBoundName(FilterBound::kMaxTruncation), "max-truncation");
  EXPECT_EQ(ParseFilterBound("min-depth"), std::nullopt);
}

// difficulty= takes KITTI's level names (any case, as --difficulties) or their index.
TEST(FilterNamesTest, DifficultyConditionByNameOrIndex) {
  const std::vector<FilterCondition> c =
      ParseFilterConditions("difficulty=easy, difficulty=Moderate,difficulty=2");
  ASSERT_EQ(c.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(c[i].bound, FilterBound::kDifficulty);
    EXPECT_EQ(c[i].value, i);
  }
  EXPECT_THROW(ParseFilterConditions("difficulty=medium"), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
