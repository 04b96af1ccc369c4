#include "stereodet/util/check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace stereodet {
namespace {

using ::testing::HasSubstr;

int CountEvaluations(int* counter) { return ++*counter; }

TEST(CheckTest, PassingCheckThrowsNothingAndDoesNotEvaluateMessage) {
  int evaluations = 0;
  EXPECT_NO_THROW(STEREODET_CHECK(1 + 1 == 2) << CountEvaluations(&evaluations));
  EXPECT_EQ(evaluations, 0);
}

TEST(CheckTest, FailingCheckThrowsInvalidArgumentWithMessageAndCondition) {
  const int block_size = 4;
  try {
    STEREODET_CHECK(block_size % 2 == 1) << "block_size must be odd, got " << block_size;
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("block_size must be odd, got 4"));
    EXPECT_THAT(e.what(), HasSubstr("block_size % 2 == 1"));
    EXPECT_THAT(e.what(), HasSubstr("check_test.cc"));
  }
}

TEST(CheckTest, IoCheckThrowsRuntimeError) {
  EXPECT_THROW(STEREODET_CHECK_IO(false) << "cannot open x", std::runtime_error);
  try {
    STEREODET_CHECK_IO(2 < 1);
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("check failed: 2 < 1"));
  }
}

TEST(CheckTest, UnconditionalThrowsLeaveOutTheCondition) {
  try {
    STEREODET_THROW_ARG() << "bad flag";
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad flag"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("false")));
  }
  EXPECT_THROW(STEREODET_THROW_IO() << "x", std::runtime_error);
}

TEST(CheckTest, WorksAsTheBodyOfAnIfWithoutBraces) {
  bool reached_else = false;
  if (false)
    STEREODET_CHECK(false) << "never";
  else
    reached_else = true;
  EXPECT_TRUE(reached_else);
}

TEST(ParseErrorTest, NamesFileLineAndField) {
  const ParseError error("label_2/000001.txt", 3, "dimensions.h", "negative value -1.5");
  EXPECT_STREQ(error.what(), "label_2/000001.txt:3: field dimensions.h: negative value -1.5");
  EXPECT_EQ(error.line(), 3);
  EXPECT_EQ(error.field(), "dimensions.h");
  const ParseError whole_file("calib/000001.txt", 0, "", "empty file");
  EXPECT_STREQ(whole_file.what(), "calib/000001.txt: empty file");
}

}  // namespace
}  // namespace stereodet
