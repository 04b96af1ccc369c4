#include "stereodet/stereo/image_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <array>
#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/stereo/disparity.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/test_temp_dir.h"

namespace stereodet {
namespace {

using ::testing::HasSubstr;

// PNG's CRC-32 (ISO 3309, reflected polynomial 0xEDB88320), bit by bit: a test needs no table.
uint32_t Crc32(const uint8_t* data, size_t size) {
  uint32_t crc = 0xFFFFFFFFu;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void PutBigEndian32(std::vector<uint8_t>* bytes, size_t at, uint32_t value) {
  for (int i = 0; i < 4; ++i) (*bytes)[at + i] = static_cast<uint8_t>(value >> (24 - 8 * i));
}

// A valid 4x4 PNG whose IHDR then claims width x height pixels, with its CRC fixed so that libpng
// reads the header without complaint.
std::string PngClaimingSize(uint32_t width, uint32_t height) {
  std::vector<uint8_t> png;
  cv::imencode(".png", cv::Mat(4, 4, CV_8UC3, cv::Scalar(1, 2, 3)), png);
  // Signature (8), IHDR length (4), "IHDR" (4), width (4), height (4), 5 more bytes, CRC (4).
  PutBigEndian32(&png, 16, width);
  PutBigEndian32(&png, 20, height);
  PutBigEndian32(&png, 29, Crc32(png.data() + 12, 17));
  return std::string(png.begin(), png.end());
}

TEST(ImageIoTest, ReadsWhatItWrote) {
  const TestTempDir temp;
  const cv::Mat image(5, 7, CV_8UC3, cv::Scalar(10, 20, 30));
  WriteImageAtomically(temp / "a.png", image);
  const cv::Mat read = ReadColourImage(temp / "a.png");
  ASSERT_EQ(read.size(), image.size());
  EXPECT_EQ(cv::norm(read, image, cv::NORM_INF), 0.0);
  // The patched-CRC writer itself is right: at its true size the PNG still reads.
  WriteFileAtomically(temp / "b.png", PngClaimingSize(4, 4));
  EXPECT_EQ(ReadColourImage(temp / "b.png").at<cv::Vec3b>(3, 3), cv::Vec3b(1, 2, 3));
}

TEST(ImageIoTest, MissingAndGarbageFilesNameThePath) {
  const TestTempDir temp;
  const std::string missing = (temp / "000001.png").string();
  try {
    ReadColourImage(missing);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot read image " + missing));
  }
  WriteFileAtomically(temp / "zero.png", "");
  EXPECT_THAT([&] { ReadColourImage(temp / "zero.png"); },
              ::testing::ThrowsMessage<std::runtime_error>(
                  HasSubstr("zero.png: not a decodable image (empty, truncated or corrupt)")));
}

TEST(ImageIoTest, AFifoInPlaceOfAnImageIsAnErrorNotAHang) {
  // cv::imread opened a FIFO and blocked forever in open(); every image goes through ReadFile.
  const TestTempDir temp;
  const std::string path = (temp / "000001.png").string();
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  try {
    ReadColourImage(path);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot read image " + path + ": not a regular file"));
  }
  EXPECT_THROW(ReadKittiDisparity(path), std::runtime_error);
}

TEST(ImageIoTest, AHeaderClaimingTenBillionPixelsIsAnErrorNamingTheFile) {
  // The audit's file: OpenCV's raw "(-215:Assertion failed) pixels <= CV_IO_MAX_IMAGE_PIXELS"
  // reached the user without the file's name.
  const TestTempDir temp;
  const std::string path = (temp / "000001.png").string();
  WriteFileAtomically(path, PngClaimingSize(100000, 100000));
  try {
    ReadColourImage(path);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot read image " + path));
  }
  try {
    ReadKittiDisparity(path);
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot read disparity image " + path));
  }
}

}  // namespace
}  // namespace stereodet
