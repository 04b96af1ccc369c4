#include <gtest/gtest.h>

#include <set>
#include <stdexcept>
#include <string>

#include "stereodet/cli/commands.h"

namespace stereodet::cli {
namespace {

TEST(CommandTableTest, NamesAreUniqueAndDescribed) {
  std::set<std::string_view> names;
  for (const Command& command : CommandTable()) {
    EXPECT_TRUE(names.insert(command.name).second) << "twice: " << command.name;
    EXPECT_FALSE(command.description.empty()) << command.name;
  }
  EXPECT_EQ(names, (std::set<std::string_view>{"synth", "stereo", "info", "eval", "calibrate",
                                               "report", "view", "train", "detect", "run"}));
}

// The front end must hold only the commands that need neither OpenCV nor LibTorch.
TEST(CommandTableTest, OwnersKeepHeavyLibrariesOutOfTheFrontEnd) {
  for (const Command& command : CommandTable()) {
    const bool light = command.name == "info" || command.name == "eval" ||
                       command.name == "calibrate" || command.name == "report" ||
                       command.name == "view";
    EXPECT_EQ(command.program == Program::kFrontEnd, light) << command.name;
  }
  EXPECT_STREQ(ProgramName(Program::kFrontEnd), "stereodet");
  EXPECT_STREQ(ProgramName(Program::kVision), "stereodet-vision");
  EXPECT_STREQ(ProgramName(Program::kModels), "stereodet-models");
  EXPECT_TRUE(ProgramBuilt(Program::kFrontEnd));
  EXPECT_TRUE(ProgramBuilt(Program::kVision));  // stereo and synth are not optional
}

TEST(CommandTableTest, ProgramNamesParseBack) {
  for (Program program : {Program::kFrontEnd, Program::kVision, Program::kModels}) {
    EXPECT_EQ(ParseProgram(ProgramName(program)), program) << ProgramName(program);
  }
  EXPECT_EQ(ParseProgram("stereodet-train"), std::nullopt);
  EXPECT_EQ(ParseProgram("./stereodet"), std::nullopt);  // a file name, not a path
}

TEST(CommandTableTest, DescriptionOfKnownAndUnknownCommands) {
  EXPECT_EQ(CommandDescription("train"), "train a detector on a KITTI-format split");
  EXPECT_THROW(CommandDescription("frobnicate"), std::logic_error);
}

}  // namespace
}  // namespace stereodet::cli
