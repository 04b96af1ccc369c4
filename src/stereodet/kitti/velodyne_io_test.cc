#include "stereodet/kitti/velodyne_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "stereodet/util/check.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

class VelodyneIoTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_.path(); }
  TestTempDir temp_;
  fs::path dir_;
};

TEST_F(VelodyneIoTest, RoundTripsExactly) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-80.0f, 80.0f);
  std::vector<VeloPoint> points(1000);
  for (VeloPoint& p : points) p = {u(rng), u(rng), u(rng) / 40.0f, std::abs(u(rng)) / 80.0f};
  const fs::path path = dir_ / "velodyne" / "000000.bin";
  WriteVelodyne(path, points);
  EXPECT_EQ(fs::file_size(path), 16000u);
  EXPECT_EQ(ReadVelodyne(path), points);
}

TEST_F(VelodyneIoTest, ReadsKittiLittleEndianLayout) {
  // Two points written as raw little-endian float32, the way KITTI's .bin files are.
  const float raw[8] = {10.5f, -2.25f, -1.75f, 0.5f, 1.0f, 2.0f, 3.0f, 0.0f};
  const fs::path path = dir_ / "raw.bin";
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(raw), sizeof(raw));
  const std::vector<VeloPoint> points = ReadVelodyne(path);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0], (VeloPoint{10.5f, -2.25f, -1.75f, 0.5f}));
  EXPECT_EQ(points[1], (VeloPoint{1.0f, 2.0f, 3.0f, 0.0f}));
}

TEST_F(VelodyneIoTest, EmptyScanIsValid) {
  WriteVelodyne(dir_ / "empty.bin", {});
  EXPECT_TRUE(ReadVelodyne(dir_ / "empty.bin").empty());
}

TEST_F(VelodyneIoTest, SizeNotAMultipleOf16IsRejectedWithTheFileName) {
  const fs::path path = dir_ / "truncated.bin";
  std::ofstream(path, std::ios::binary) << std::string(16 * 3 + 7, '\0');
  try {
    ReadVelodyne(path);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(path.string()));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("55 bytes is not a multiple of 16"));
  }
  EXPECT_THROW(ReadVelodyne(dir_ / "missing.bin"), std::runtime_error);
}

// A scan whose reflectances are all NaN used to become an empty scan downstream, silently.
TEST_F(VelodyneIoTest, ANonFiniteValueIsRefusedNamingThePointAndField) {
  const fs::path path = dir_ / "nan.bin";
  std::vector<VeloPoint> points = {{1, 2, 3, 0.5f}, {4, 5, 6, 0.5f}};
  points[1].reflectance = std::numeric_limits<float>::quiet_NaN();
  WriteVelodyne(path, points);
  try {
    ReadVelodyne(path);
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.field(), "point 1 reflectance");
  }
  points[1].reflectance = 0.5f;
  points[0].z = std::numeric_limits<float>::infinity();
  WriteVelodyne(path, points);
  EXPECT_THROW(ReadVelodyne(path), ParseError);
}

}  // namespace
}  // namespace stereodet
