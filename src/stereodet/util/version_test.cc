#include "stereodet/util/version.h"

#include <gtest/gtest.h>

#include <regex>
#include <string>

namespace stereodet {
namespace {

TEST(VersionTest, IsTheProjectsDottedVersion) {
  // Not "unknown", which results.json recorded while only the CLI knew the version.
  EXPECT_TRUE(std::regex_match(std::string(StereodetVersion()), std::regex(R"(\d+\.\d+\.\d+)")))
      << StereodetVersion();
}

}  // namespace
}  // namespace stereodet
