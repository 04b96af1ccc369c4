#include "stereodet/models/ssd/input_encoding.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace stereodet {
namespace {

cv::Mat TestImage() {
  cv::Mat bgr(2, 3, CV_8UC3);
  // pixel (0, 0): B = 255, G = 8, R = 7;  every other pixel: B = 0, G = 128, R = 255
  bgr.setTo(cv::Scalar(0, 128, 255));
  bgr.at<cv::Vec3b>(0, 0) = cv::Vec3b(255, 8, 7);
  return bgr;
}

cv::Mat TestHeight() {
  cv::Mat height(2, 3, CV_16UC1, cv::Scalar(511));
  height.at<uint16_t>(0, 0) = 0;  // no stereo
  height.at<uint16_t>(1, 0) = 100;
  return height;
}

void ExpectInUnitRange(const PlanarImage& p) {
  EXPECT_GE(*std::min_element(p.data.begin(), p.data.end()), 0.0f);
  EXPECT_LE(*std::max_element(p.data.begin(), p.data.end()), 1.0f);
}

TEST(InputEncodingTest, NamesRoundTrip) {
  for (InputEncoding e :
       {InputEncoding::kRgb, InputEncoding::kRgbhFixed, InputEncoding::kRgbhLearned}) {
    EXPECT_EQ(ParseInputEncoding(InputEncodingName(e)), e);
  }
  EXPECT_EQ(ParseInputEncoding("rgbd"), std::nullopt);
  EXPECT_EQ(ParseInputEncoding("RGB"), std::nullopt);
  EXPECT_EQ(NetworkInputChannels(InputEncoding::kRgb), 3);
  EXPECT_EQ(NetworkInputChannels(InputEncoding::kRgbhFixed), 3);
  EXPECT_EQ(NetworkInputChannels(InputEncoding::kRgbhLearned), 4);
}

TEST(InputEncodingTest, RgbIsColourOver255InRgbOrder) {
  const PlanarImage p = EncodeNetworkInput(TestImage(), {}, InputEncoding::kRgb);
  ASSERT_EQ(p.channels, 3);
  ASSERT_EQ(p.rows, 2);
  ASSERT_EQ(p.cols, 3);
  EXPECT_FLOAT_EQ(p.At(0, 0, 0), 7 / 255.0f);
  EXPECT_FLOAT_EQ(p.At(1, 0, 0), 8 / 255.0f);
  EXPECT_FLOAT_EQ(p.At(2, 0, 0), 1.0f);
  ExpectInUnitRange(p);
}

TEST(InputEncodingTest, LearnedIsFiveBitColourPlusNineBitHeight) {
  const PlanarImage p = EncodeNetworkInput(TestImage(), TestHeight(), InputEncoding::kRgbhLearned);
  ASSERT_EQ(p.channels, 4);
  EXPECT_FLOAT_EQ(p.At(0, 0, 0), 0.0f);       // 7 >> 3
  EXPECT_FLOAT_EQ(p.At(1, 0, 0), 1 / 31.0f);  // 8 >> 3
  EXPECT_FLOAT_EQ(p.At(2, 0, 0), 1.0f);       // 255 >> 3 = 31
  EXPECT_FLOAT_EQ(p.At(3, 0, 0), 0.0f);       // no stereo
  EXPECT_FLOAT_EQ(p.At(0, 1, 2), 1.0f);
  EXPECT_FLOAT_EQ(p.At(1, 1, 2), 16 / 31.0f);  // 128 >> 3
  EXPECT_FLOAT_EQ(p.At(3, 1, 2), 1.0f);
  EXPECT_FLOAT_EQ(p.At(3, 1, 0), 100 / 511.0f);
  ExpectInUnitRange(p);
}

TEST(InputEncodingTest, FixedIsTwoColourChannelsPlusHeight) {
  const PlanarImage p = EncodeNetworkInput(TestImage(), TestHeight(), InputEncoding::kRgbhFixed);
  ASSERT_EQ(p.channels, 3);
  // Pixel (1, 2): r = 1, g = 16/31, b = 0.
  EXPECT_NEAR(p.At(0, 1, 2), kLumaR * 1.0f + kLumaG * 16 / 31.0f, 1e-6);
  EXPECT_NEAR(p.At(1, 1, 2), 0.5f + 0.5f * (1.0f - 0.0f), 1e-6);
  EXPECT_FLOAT_EQ(p.At(2, 1, 2), 1.0f);
  EXPECT_FLOAT_EQ(p.At(2, 1, 0), 100 / 511.0f);
  ExpectInUnitRange(p);
}

TEST(InputEncodingTest, HeightMustMatchTheImage) {
  const cv::Mat height(4, 4, CV_16UC1, cv::Scalar(1));
  EXPECT_THROW(EncodeNetworkInput(TestImage(), height, InputEncoding::kRgbhLearned),
               std::invalid_argument);
  EXPECT_THROW(EncodeNetworkInput(TestImage(), cv::Mat(), InputEncoding::kRgbhFixed),
               std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
