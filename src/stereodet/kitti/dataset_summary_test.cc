#include "stereodet/kitti/dataset_summary.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

void Write(const fs::path& path, const std::string& contents) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << contents;
}

// Easy (h 165 px, occ 0, trunc 0), 8.41 m away.
constexpr char kEasyPedestrian[] =
    "Pedestrian 0.00 0 -0.20 712.40 143.00 810.73 307.92 1.89 0.48 1.20 1.84 1.47 8.41 0.01\n";
// Moderate only (occluded 1), 58.49 m... sqrt(16.53^2 + 58.49^2) = 60.78 m.
constexpr char kModerateCar[] =
    "Car 0.00 1 1.85 387.63 181.54 423.81 223.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n";
// Hard only (truncated 0.4), 15 m.
constexpr char kHardCar[] =
    "Car 0.40 0 1.85 387.63 181.54 423.81 223.12 1.67 1.87 3.69 9.00 1.60 12.00 1.57\n";
// None (20 px tall), 25 m.
constexpr char kTinyCyclist[] =
    "Cyclist 0.00 0 1.94 330.06 176.41 355.61 196.41 1.72 0.50 1.95 -15.00 1.88 20.00 1.56\n";
constexpr char kDontCare[] =
    "DontCare -1 -1 -10 503.89 169.71 590.61 190.13 -1 -1 -1 -1000 -1000 -1000 -10\n";

class DatasetSummaryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = temp_.path();
    const fs::path training = root_ / "training";
    Write(training / "label_2" / "000000.txt", std::string(kEasyPedestrian) + kDontCare);
    Write(training / "label_2" / "000001.txt", std::string(kModerateCar) + kHardCar + kTinyCyclist);
    Write(training / "label_2" / "000002.txt", "");
    for (const char* id : {"000000", "000001", "000002"}) {
      WriteCalibration(training / "calib" / (std::string(id) + ".txt"), KittiLikeCalibration());
    }
    options_.progress.stream = nullptr;
  }
  TestTempDir temp_;

  fs::path root_;
  DatasetSummaryOptions options_;
};

TEST_F(DatasetSummaryTest, CountsClassesDifficultiesAndDistances) {
  const KittiDataset dataset(root_);
  const DatasetSummary s = SummarizeDataset(dataset, {}, options_);
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.frames_with_labels, 3);
  EXPECT_EQ(s.objects, 5);
  ASSERT_EQ(s.classes.size(), 4u);
  const ClassCounts& car = s.classes.at("Car");
  EXPECT_EQ(car.objects, 2);
  EXPECT_THAT(car.by_difficulty, ElementsAre(0, 1, 1, 0));
  EXPECT_THAT(s.classes.at("Pedestrian").by_difficulty, ElementsAre(1, 0, 0, 0));
  EXPECT_THAT(s.classes.at("Cyclist").by_difficulty, ElementsAre(0, 0, 0, 1));
  EXPECT_THAT(s.classes.at("DontCare").by_difficulty, ElementsAre(0, 0, 0, 1));
  // 8.41 m -> bin 0; 15 m -> bin 1; 25 m -> bin 2; 60.78 m -> bin 6. DontCare excluded.
  EXPECT_THAT(s.distance_histogram, ElementsAre(1, 1, 1, 0, 0, 0, 1));
  EXPECT_THAT(car.distance_histogram, ElementsAre(0, 1, 0, 0, 0, 0, 1));
  EXPECT_TRUE(s.classes.at("DontCare").distance_histogram.empty());
  EXPECT_EQ(s.frames_with_calib, 3);
  EXPECT_DOUBLE_EQ(s.min_focal_px, 721.5377);
  EXPECT_NEAR(s.max_baseline_m, 0.532, 0.01);
  EXPECT_FALSE(s.HasProblems());
}

TEST_F(DatasetSummaryTest, SplitAndBinWidth) {
  const KittiDataset dataset(root_);
  options_.distance_bin_m = 20.0;
  const DatasetSummary s = SummarizeDataset(dataset, {"000001"}, options_);
  EXPECT_EQ(s.frames, 1);
  EXPECT_EQ(s.objects, 3);
  EXPECT_THAT(s.distance_histogram, ElementsAre(1, 1, 0, 1));  // 15, 25, 60.78 m
  options_.distance_bin_m = 0;
  EXPECT_THROW(SummarizeDataset(dataset, {}, options_), std::invalid_argument);
}

TEST_F(DatasetSummaryTest, ReportsMissingFilesPerFrame) {
  fs::remove(root_ / "training" / "calib" / "000001.txt");
  fs::create_directories(root_ / "training" / "velodyne");  // the folder exists: scans are expected
  const DatasetSummary s =
      SummarizeDataset(KittiDataset(root_), {"000000", "000001", "000007"}, options_);
  EXPECT_TRUE(s.HasProblems());
  EXPECT_THAT(s.missing_files,
              ElementsAre("000000: velodyne/000000.bin", "000001: calib/000001.txt",
                          "000001: velodyne/000001.bin", "000007: label_2/000007.txt",
                          "000007: calib/000007.txt", "000007: velodyne/000007.bin"));
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.frames_with_labels, 2);
  EXPECT_EQ(s.frames_with_calib, 1);
}

TEST_F(DatasetSummaryTest, ZeroByteAndTruncatedImagesAndOddScansAreProblems) {
  // The audit: these passed `info` although the docs said they are rejected.
  const fs::path training = root_ / "training";
  const std::string png(
      "\x89PNG\r\n\x1a\n"
      "\0\0\0\x0dIHDR\0\0\0\x01\0\0\0\x01\x08\x06\0\0\0\x1f\x15\xc4\x89"
      "\0\0\0\x0aIDAT\x78\x9c\x63\0\x01\0\0\x05\0\x01\x0d\x0a\x2d\xb4"
      "\0\0\0\0IEND\xae\x42\x60\x82",
      67);
  for (const char* id : {"000000", "000001", "000002"}) {
    Write(training / "image_2" / (std::string(id) + ".png"), png);
    Write(training / "image_3" / (std::string(id) + ".png"), png);
    Write(training / "velodyne" / (std::string(id) + ".bin"), std::string(32, '\0'));
  }
  const KittiDataset dataset(root_);
  EXPECT_FALSE(SummarizeDataset(dataset, {}, options_).HasProblems());

  Write(training / "image_2" / "000001.png", "");
  Write(training / "image_3" / "000002.png", png.substr(0, 50));
  Write(training / "velodyne" / "000002.bin", std::string(17, '\0'));
  const DatasetSummary s = SummarizeDataset(dataset, {}, options_);
  ASSERT_EQ(s.bad_files.size(), 3u);
  EXPECT_THAT(s.bad_files[0], HasSubstr("image_2/000001.png: not a PNG image (0 bytes"));
  EXPECT_THAT(s.bad_files[1], HasSubstr("image_3/000002.png: truncated PNG image (50 bytes"));
  EXPECT_THAT(s.bad_files[2], HasSubstr("velodyne/000002.bin: a velodyne scan must be"));
  EXPECT_TRUE(s.missing_files.empty());
}

TEST_F(DatasetSummaryTest, StrictReportsBadFilesLenientSkipsLines) {
  Write(root_ / "training" / "label_2" / "000002.txt",
        std::string(kHardCar) + "Car 0.00 0 1.85 1 2 3 4 -2.00 1.87 3.69 1 2 3 1.57\n");
  Write(root_ / "training" / "calib" / "000002.txt", "P0: 1 2 3\n");
  const KittiDataset dataset(root_);
  const DatasetSummary strict = SummarizeDataset(dataset, {}, options_);
  EXPECT_TRUE(strict.HasProblems());
  ASSERT_EQ(strict.bad_files.size(), 2u);
  EXPECT_THAT(strict.bad_files[0], HasSubstr("label_2/000002.txt:2: field dimensions.h:"));
  EXPECT_THAT(strict.bad_files[1], HasSubstr("calib/000002.txt:1: field P0:"));
  EXPECT_EQ(strict.objects, 5);  // the bad file's good line is not counted either

  options_.lenient = true;
  const DatasetSummary lenient = SummarizeDataset(dataset, {}, options_);
  EXPECT_EQ(lenient.objects, 6);
  EXPECT_EQ(lenient.skipped_lines, 1);
  ASSERT_EQ(lenient.skipped.size(), 1u);
  EXPECT_THAT(lenient.skipped[0], HasSubstr("label_2/000002.txt:2: field dimensions.h:"));
  ASSERT_EQ(lenient.bad_files.size(), 1u);  // the calib file is still bad
  EXPECT_TRUE(lenient.HasProblems());
}

TEST_F(DatasetSummaryTest, TestingSubsetNeedsNoLabels) {
  WriteCalibration(root_ / "testing" / "calib" / "000000.txt", KittiLikeCalibration());
  const DatasetSummary s = SummarizeDataset(KittiDataset(root_, "testing"), {}, options_);
  EXPECT_EQ(s.frames, 1);
  EXPECT_EQ(s.objects, 0);
  EXPECT_FALSE(s.HasProblems());
}

TEST_F(DatasetSummaryTest, FarAwayLabelsDoNotBlowUpTheHistogram) {
  Write(root_ / "training" / "label_2" / "000002.txt",
        "Car 0.00 0 0 1 2 3 50 1.5 1.6 3.9 1e300 1.6 1e300 0\n");
  const DatasetSummary s = SummarizeDataset(KittiDataset(root_), {"000002"}, options_);
  EXPECT_EQ(s.distance_histogram.size(), 1000u);
  EXPECT_EQ(s.distance_histogram.back(), 1);
}

TEST(DifficultyBucketTest, NamesParseBack) {
  for (int i = 0; i < kNumDifficultyBuckets; ++i) {
    const auto bucket = static_cast<DifficultyBucket>(i);
    EXPECT_EQ(ParseDifficultyBucket(DifficultyBucketName(bucket)), bucket)
        << DifficultyBucketName(bucket);
  }
  EXPECT_STREQ(DifficultyBucketName(DifficultyBucket::kModerateOnly), "moderate_only");
  for (const char* bad : {"", "moderate", "Easy", "hard only", "?"}) {
    EXPECT_EQ(ParseDifficultyBucket(bad), std::nullopt) << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace stereodet
