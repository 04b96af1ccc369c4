#include "stereodet/eval/eval_options.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace stereodet {
namespace {

TEST(EvalOptions, CompatNamesRoundTrip) {
  for (EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    EXPECT_EQ(ParseEvalCompat(EvalCompatName(c)), c);
  }
  EXPECT_EQ(ParseEvalCompat("OpenPCDet"), EvalCompat::kOpenPcdet);
  EXPECT_FALSE(ParseEvalCompat("mmdet").has_value());
}

TEST(EvalOptions, OpenPcdetCompatNeedsTheKittiMatcher) {
  EvalOptions options;
  options.compat = EvalCompat::kOpenPcdet;
  EXPECT_NO_THROW(options.Check());
  options.matcher = Matcher::kOptimal;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

// Option checks name the field and its value (the comparison checks of util/check.h).
TEST(EvalOptions, CheckMessagesNameTheFieldAndItsValue) {
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
  EXPECT_NE(message(o).find("distance_bin_m = -5, must be > 0"), std::string::npos) << message(o);
  o = EvalOptions();
  o.distance_bin_m = 1e-4;
  EXPECT_NE(message(o).find("must be <= 100000 (localization bins)"), std::string::npos)
      << message(o);
}

}  // namespace
}  // namespace stereodet
