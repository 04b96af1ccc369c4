#include "stereodet/util/strings.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

namespace stereodet {
namespace {

TEST(StringsTest, ParseDoubleAcceptsOnlyWholeNumbers) {
  EXPECT_EQ(ParseDouble("1.5"), 1.5);
  EXPECT_EQ(ParseDouble("-2e-3"), -2e-3);
  EXPECT_EQ(ParseDouble("+7"), 7.0);
  EXPECT_FALSE(ParseDouble(""));
  EXPECT_FALSE(ParseDouble("1.5x"));
  EXPECT_FALSE(ParseDouble(" 1"));
  EXPECT_FALSE(ParseDouble("Car"));
  EXPECT_FALSE(ParseDouble("1e999"));
  EXPECT_FALSE(ParseDouble("+-1"));
  EXPECT_FALSE(ParseDouble("++1"));
  EXPECT_FALSE(ParseInt("+-1"));
  EXPECT_TRUE(std::isnan(*ParseDouble("nan")));
  EXPECT_TRUE(std::isinf(*ParseDouble("-inf")));
  EXPECT_EQ(ParseInt("42"), 42);
  EXPECT_FALSE(ParseInt("4.2"));
  EXPECT_EQ(ParseFloat("0.1"), 0.1f);
}

TEST(StringsTest, SplitWhitespaceDropsEmptyTokens) {
  const auto tokens = SplitWhitespace("  Car 0.00\t1 \r\n");
  ASSERT_EQ(tokens.size(), 3u);
  EXPECT_EQ(tokens[0], "Car");
  EXPECT_EQ(tokens[2], "1");
  EXPECT_TRUE(SplitWhitespace(" \t ").empty());
}

TEST(StringsTest, SplitKeepsEmptyTokensAndTrimTrims) {
  const auto tokens = Split("a,,b", ',');
  ASSERT_EQ(tokens.size(), 3u);
  EXPECT_EQ(tokens[1], "");
  EXPECT_EQ(Trim("  x y \n"), "x y");
}

TEST(StringsTest, FormatShortestRoundTripsRandomValues) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> dist(-1e4, 1e4);
  for (int i = 0; i < 10000; ++i) {
    const double d = dist(rng);
    ASSERT_EQ(ParseDouble(FormatShortest(d)), d);
    const float f = static_cast<float>(d);
    ASSERT_EQ(ParseFloat(FormatShortest(f)), f);
  }
  EXPECT_EQ(FormatShortest(1.5), "1.5");
  EXPECT_EQ(FormatShortest(0.1f), "0.1");
}

std::string FmtShortest(double value) {
  std::string text = "x";  // appends, keeps what was there
  AppendFmtShortest(text, value);
  return text.substr(1);
}

TEST(StringsTest, AppendFmtShortestWritesFmtsTextForEveryKindOfDouble) {
  EXPECT_EQ(FmtShortest(1.0), "1");
  EXPECT_EQ(FmtShortest(0.5), "0.5");
  EXPECT_EQ(FmtShortest(0.0001), "0.0001");
  EXPECT_EQ(FmtShortest(1e-05), "1e-05");
  EXPECT_EQ(FmtShortest(1e16), "1e+16");
  EXPECT_EQ(FmtShortest(1234567890123456.0), "1234567890123456");
  EXPECT_EQ(FmtShortest(-0.0), "-0");
  EXPECT_EQ(FmtShortest(0.0), "0");
  EXPECT_EQ(FmtShortest(1e300), "1e+300");
  EXPECT_EQ(FmtShortest(-2.5e-310), "-2.5e-310");
  // Against fmt itself: edge values, random bit patterns (every exponent, subnormals, NaN and
  // infinities among them), and two-decimal and ratio values as the curves hold.
  std::vector<double> values = {std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::denorm_min(),
                                std::numeric_limits<double>::infinity(),
                                -std::numeric_limits<double>::infinity(),
                                std::nan(""),
                                1e15,
                                9.999999999999999e15,
                                1e-4,
                                9.99999e-5,
                                123.0,
                                100.0,
                                1.0 / 3.0};
  std::mt19937_64 rng(11);
  for (int i = 0; i < 200000; ++i) values.push_back(std::bit_cast<double>(rng()));
  std::uniform_int_distribution<int> count(0, 5000);
  for (int i = 0; i < 200000; ++i) {
    const int a = count(rng), b = count(rng) + 1;
    values.push_back(static_cast<double>(a) / b);
    values.push_back(static_cast<double>(a) / 100.0);
    values.push_back(static_cast<double>(a) * std::pow(10.0, count(rng) % 40 - 20));
  }
  for (double v : values) ASSERT_EQ(FmtShortest(v), fmt::format("{}", v)) << fmt::format("{}", v);
}

TEST(StringsTest, AppendIntAppendsTheDecimalText) {
  std::string text = "n=";
  AppendInt(text, -12);
  AppendInt(text, 0);
  AppendInt(text, std::numeric_limits<int64_t>::min());
  EXPECT_EQ(text, "n=-120-9223372036854775808");
}

}  // namespace
TEST(StringsTest, EqualsIgnoreCaseComparesAsciiLettersOnlyCaseInsensitively) {
  EXPECT_TRUE(EqualsIgnoreCase("DontCare", "dontcare"));
  EXPECT_TRUE(EqualsIgnoreCase("", ""));
  EXPECT_FALSE(EqualsIgnoreCase("Car", "Cars"));
  EXPECT_FALSE(EqualsIgnoreCase("Car", "Bar"));
  EXPECT_FALSE(
      EqualsIgnoreCase("\xc3\x84", "\xc3\xa4"));  // UTF-8 letters are compared byte for byte
  EXPECT_FALSE(
      EqualsIgnoreCase("a[", "A{"));  // '[' and '{' differ by the case bit, but are no letters
}

TEST(StringsTest, StripUtf8BomRemovesOnlyALeadingMark) {
  EXPECT_EQ(StripUtf8Bom("\xEF\xBB\xBF"
                         "Car 0"),
            "Car 0");
  EXPECT_EQ(StripUtf8Bom("Car 0"), "Car 0");
  EXPECT_EQ(StripUtf8Bom("\xEF\xBB\xBF"), "");
  EXPECT_EQ(StripUtf8Bom(""), "");
  EXPECT_EQ(StripUtf8Bom("\xEF\xBB"), "\xEF\xBB");            // a part of one: kept
  EXPECT_EQ(StripUtf8Bom("x\xEF\xBB\xBF"), "x\xEF\xBB\xBF");  // not at the start
  EXPECT_EQ(StripUtf8Bom("\xEF\xBB\xBF\xEF\xBB\xBF"
                         "a"),
            "\xEF\xBB\xBF"
            "a");  // only one
}

}  // namespace stereodet
