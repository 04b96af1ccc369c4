#include "stereodet/kitti/dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

void Touch(const fs::path& path, const std::string& contents = "") {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << contents;
}

class DatasetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = temp_.path();
    fs::create_directories(root_ / "training");
  }
  TestTempDir temp_;
  fs::path root_;
};

TEST_F(DatasetTest, RequiresTheSubsetFolder) {
  EXPECT_NO_THROW(KittiDataset(root_, "training"));
  try {
    KittiDataset(root_, "testing");
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("testing"));
    EXPECT_THAT(e.what(), HasSubstr("is not a folder"));
  }
}

TEST_F(DatasetTest, PathsFollowTheKittiLayout) {
  const KittiDataset dataset(root_);
  const FramePaths p = dataset.Paths("000123");
  EXPECT_EQ(p.id, "000123");
  EXPECT_EQ(p.image_left, root_ / "training" / "image_2" / "000123.png");
  EXPECT_EQ(p.image_right, root_ / "training" / "image_3" / "000123.png");
  EXPECT_EQ(p.label, root_ / "training" / "label_2" / "000123.txt");
  EXPECT_EQ(p.calib, root_ / "training" / "calib" / "000123.txt");
  EXPECT_EQ(p.velodyne, root_ / "training" / "velodyne" / "000123.bin");
  EXPECT_EQ(p.disparity, root_ / "training" / "disp_noc_0" / "000123.png");
  EXPECT_EQ(dataset.SubsetDir(), root_ / "training");
}

TEST_F(DatasetTest, ListIdsPrefersImagesThenLabelsThenCalib) {
  const KittiDataset dataset(root_);
  EXPECT_TRUE(dataset.ListIds().empty());
  Touch(root_ / "training" / "calib" / "000009.txt");
  EXPECT_THAT(dataset.ListIds(), ElementsAre("000009"));
  Touch(root_ / "training" / "label_2" / "000002.txt");
  Touch(root_ / "training" / "label_2" / "000001.txt");
  Touch(root_ / "training" / "label_2" / ".000003.txt.tmp-1234");  // a half-written file
  Touch(root_ / "training" / "label_2" / "notes.txt");
  EXPECT_THAT(dataset.ListIds(), ElementsAre("000001", "000002"));
  Touch(root_ / "training" / "image_2" / "000010.png");
  Touch(root_ / "training" / "image_2" / "000005.png");
  Touch(root_ / "training" / "image_2" / "000005.jpg");
  EXPECT_THAT(dataset.ListIds(), ElementsAre("000005", "000010"));
}

TEST_F(DatasetTest, ListIdsSortsNumerically) {
  const KittiDataset dataset(root_);
  for (const char* id : {"1000000", "999999", "000000"}) {
    Touch(root_ / "training" / "label_2" / (std::string(id) + ".txt"));
  }
  EXPECT_THAT(dataset.ListIds(), ElementsAre("000000", "999999", "1000000"));
}

TEST_F(DatasetTest, ReadSplitByPathOrByName) {
  const KittiDataset dataset(root_);
  Touch(root_ / "ImageSets" / "val.txt", "000001\n000007\r\n\n  000003  \n");
  EXPECT_THAT(dataset.ReadSplit("val"), ElementsAre("000001", "000007", "000003"));
  EXPECT_THAT(dataset.ReadSplit("val.txt"), ElementsAre("000001", "000007", "000003"));
  EXPECT_THAT(dataset.ReadSplit(root_ / "ImageSets" / "val.txt"),
              ElementsAre("000001", "000007", "000003"));
  EXPECT_THROW(dataset.ReadSplit("train"), std::runtime_error);
}

TEST_F(DatasetTest, ReadSplitRejectsNonIdsWithFileAndLine) {
  const KittiDataset dataset(root_);
  Touch(root_ / "ImageSets" / "bad.txt", "000001\n00000x\n");
  try {
    dataset.ReadSplit("bad");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), (root_ / "ImageSets" / "bad.txt").string());
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.field(), "frame id");
    EXPECT_THAT(e.message(), HasSubstr("'00000x'"));
  }
}

TEST(ParseSplitTest, ALeadingByteOrderMarkIsIgnoredAndANulByteIsNamedEscaped) {
  EXPECT_THAT(ParseSplit("\xEF\xBB\xBF"
                         "000004\n000002\n",
                         "s.txt"),
              ElementsAre("000004", "000002"));
  try {
    ParseSplit(std::string("000001\n0000\0"
                           "2\n",
                           13),
               "s.txt");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), "s.txt");
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.field(), "frame id");
    EXPECT_THAT(e.message(), HasSubstr("'0000\\x002'"));
  }
  try {
    ParseSplit(std::string(1000000, '7') + "x\n", "s.txt");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_LT(e.message().size(), 200u);  // shortened, not echoed in full
  }
}

TEST_F(DatasetTest, WriteSplitRoundTrips) {
  const KittiDataset dataset(root_);
  const std::vector<std::string> ids = {"000004", "000002", "000100"};
  WriteSplit(root_ / "ImageSets" / "mine.txt", ids);
  EXPECT_EQ(dataset.ReadSplit("mine"), ids);
  EXPECT_THROW(WriteSplit(root_ / "ImageSets" / "bad.txt", {"12a"}), std::invalid_argument);
}

TEST_F(DatasetTest, FindMissingFilesListsEachMissingFileInIdOrder) {
  const KittiDataset dataset(root_);
  Touch(root_ / "training" / "label_2" / "000001.txt");
  Touch(root_ / "training" / "calib" / "000001.txt");
  Touch(root_ / "training" / "label_2" / "000002.txt");
  RequiredFiles required;
  required.label = required.calib = true;
  EXPECT_THAT(FindMissingFiles(dataset, {"000003", "000001", "000002"}, required),
              ElementsAre("000002: calib/000002.txt", "000003: label_2/000003.txt",
                          "000003: calib/000003.txt"));
  required.image_left = required.velodyne = true;
  EXPECT_THAT(FindMissingFiles(dataset, {"000001"}, required),
              ElementsAre("000001: image_2/000001.png", "000001: velodyne/000001.bin"));
  EXPECT_TRUE(FindMissingFiles(dataset, {"000001"}, RequiredFiles{}).empty());
}

TEST(FrameIdTest, PadsToSixDigits) {
  EXPECT_EQ(FrameId(0), "000000");
  EXPECT_EQ(FrameId(123), "000123");
  EXPECT_EQ(FrameId(999999), "999999");
  EXPECT_EQ(FrameId(1234567), "1234567");
  EXPECT_THROW(FrameId(-1), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
