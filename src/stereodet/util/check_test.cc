#include "stereodet/util/check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>

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

// A streamed operand whose own check fails: its exception propagates (before the guard in
// ~CheckFailure this was std::terminate, exit 134).
std::string Describe(int value) {
  STEREODET_CHECK(value >= 0) << "cannot describe " << value;
  return std::to_string(value);
}

TEST(CheckTest, AFailingCheckInsideTheMessagePropagatesInsteadOfAborting) {
  try {
    STEREODET_CHECK_IO(false) << "outer: " << Describe(-3);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {  // the inner check's kind, not the outer's
    EXPECT_THAT(e.what(), HasSubstr("cannot describe -3"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("outer")));
  }
}

TEST(CheckTest, ChecksInsideAnUnwindingDestructorStillThrow) {
  // A check that starts while another exception is in flight (here in a destructor during
  // unwinding, caught there) still throws its own.
  struct Cleanup {
    bool* caught;
    ~Cleanup() {
      try {
        STEREODET_CHECK(false) << "inner";
      } catch (const std::invalid_argument&) {
        *caught = true;
      }
    }
  };
  bool caught = false;
  try {
    Cleanup c{&caught};
    throw std::runtime_error("outer");
  } catch (const std::runtime_error&) {
  }
  EXPECT_TRUE(caught);
}

TEST(CheckTest, ComparisonChecksDescribeThemselves) {
  const int calibration_bins = 0;
  try {
    STEREODET_CHECK_GE(calibration_bins, 1) << " (--calibration-bins)";
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("calibration_bins = 0, must be >= 1 (--calibration-bins)"));
    EXPECT_THAT(e.what(), HasSubstr("calibration_bins >= 1"));
  }
  const double lower = 5.0, upper = 3.5;
  try {
    STEREODET_CHECK_LT(lower, upper);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("lower = 5, must be < upper (3.5)"));
  }
  EXPECT_THROW(STEREODET_CHECK_IO_EQ(2, 3), std::runtime_error);
  EXPECT_NO_THROW(STEREODET_CHECK_EQ(2, 2));
  EXPECT_NO_THROW(STEREODET_CHECK_NE(2, 3) << "never built");
  EXPECT_THROW(STEREODET_CHECK_LE(4, 3), std::invalid_argument);
  EXPECT_THROW(STEREODET_CHECK_GT(3, 3), std::invalid_argument);
}

TEST(CheckTest, ComparisonChecksEvaluateEachOperandOnce) {
  int evaluations = 0;
  EXPECT_NO_THROW(STEREODET_CHECK_GE(CountEvaluations(&evaluations), 1));
  EXPECT_EQ(evaluations, 1);
  EXPECT_THROW(STEREODET_CHECK_LT(CountEvaluations(&evaluations), 0), std::invalid_argument);
  EXPECT_EQ(evaluations, 2);
  bool reached_else = false;
  if (false)
    STEREODET_CHECK_EQ(1, 2) << "never";
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

TEST(StripSourceTagsTest, RemovesEveryTagAChecksAppends) {
  EXPECT_EQ(StripSourceTags("bad flag [synth_command.cc:42]"), "bad flag");
  EXPECT_EQ(StripSourceTags("x = 0, must be >= 1 [check_test.cc:7, x >= 1]"),
            "x = 0, must be >= 1");
  // Nested: a caller wrapped a check's message and threw its own.
  EXPECT_EQ(StripSourceTags("frame 000007: boxes[2] is empty [a.h:3, boxes[i].size() > 0]; "
                            "retrain [b-c_d.cpp:10]"),
            "frame 000007: boxes[2] is empty; retrain");
  EXPECT_EQ(StripSourceTags("no tag here"), "no tag here");
  EXPECT_EQ(StripSourceTags(""), "");
}

TEST(StripSourceTagsTest, LeavesOtherBracketsAlone) {
  // Not a source file, no line, no space before the bracket, a tag that never closes.
  EXPECT_EQ(StripSourceTags("AP [0.5:1]"), "AP [0.5:1]");
  EXPECT_EQ(StripSourceTags("bins [a.cc:]"), "bins [a.cc:]");
  EXPECT_EQ(StripSourceTags("x[a.cc:3]"), "x[a.cc:3]");
  EXPECT_EQ(StripSourceTags("x [a.cc:3, y[0]"), "x [a.cc:3, y[0]");
  EXPECT_EQ(StripSourceTags("x [a.cc:3; y]"), "x [a.cc:3; y]");
  EXPECT_EQ(StripSourceTags("range [0, 50) m"), "range [0, 50) m");
}

TEST(StripSourceTagsTest, StripsWhatEveryCheckMacroThrows) {
  const auto message_of = [](const auto& throwing) {
    try {
      throwing();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  const int size = 0;
  EXPECT_EQ(StripSourceTags(message_of([&] { STEREODET_CHECK(size > 0) << "empty"; })), "empty");
  EXPECT_EQ(StripSourceTags(message_of([&] { STEREODET_CHECK(size > 0); })),
            "check failed: size > 0");
  EXPECT_EQ(StripSourceTags(message_of([&] { STEREODET_CHECK_GE(size, 1) << " (--n)"; })),
            "size = 0, must be >= 1 (--n)");
  EXPECT_EQ(StripSourceTags(message_of([] { STEREODET_THROW_IO() << "cannot read a [x]"; })),
            "cannot read a [x]");
  const int values[2] = {1, 2};
  EXPECT_EQ(StripSourceTags(message_of([&] { STEREODET_CHECK(values[size] > 1) << "v"; })), "v");
}

TEST(UserMessageTest, StripsUnlessDebugMessagesAreOn) {
  const std::invalid_argument error("bad flag [synth_command.cc:42, n > 0]");
  ::unsetenv("STEREODET_DEBUG");
  EXPECT_EQ(UserMessage(error), "bad flag");
  SetDebugMessages(true);
  EXPECT_EQ(UserMessage(error), error.what());
  SetDebugMessages(false);
  ::setenv("STEREODET_DEBUG", "1", 1);
  EXPECT_EQ(UserMessage(error), error.what());
  ::setenv("STEREODET_DEBUG", "0", 1);
  EXPECT_EQ(UserMessage(error), "bad flag");
  ::setenv("STEREODET_DEBUG", "", 1);
  EXPECT_EQ(UserMessage(error), "bad flag");
  ::unsetenv("STEREODET_DEBUG");
}

}  // namespace
}  // namespace stereodet
