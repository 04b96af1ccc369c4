#include "stereodet/stereo/rgbh.h"

#include <gtest/gtest.h>

namespace stereodet {
namespace {

TEST(RgbhTest, PacksTheDocumentedBitLayout) {
  cv::Mat bgr(1, 1, CV_8UC3, cv::Scalar(0b10101111, 0b01010111, 0b11001101));  // B, G, R
  cv::Mat height(1, 1, CV_16UC1, cv::Scalar(0b101'100'111));
  const cv::Vec3b packed = PackRgbh(bgr, height).at<cv::Vec3b>(0, 0);
  EXPECT_EQ(packed[0], 0b10101'111);  // B: b5 | h2..h0
  EXPECT_EQ(packed[1], 0b01010'100);  // G: g5 | h5..h3
  EXPECT_EQ(packed[2], 0b11001'101);  // R: r5 | h8..h6
}

TEST(RgbhTest, PackThenUnpackIsLosslessFor5BitColourAnd9BitHeight) {
  // Every height code and every 5-bit colour value, plus random pixels.
  cv::Mat bgr(64, 512, CV_8UC3), height(64, 512, CV_16UC1);
  cv::RNG rng(5);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  rng.fill(height, cv::RNG::UNIFORM, 0, 512);
  for (int u = 0; u < 512; ++u) {
    height.at<uint16_t>(0, u) = static_cast<uint16_t>(u);
    const auto c = static_cast<uint8_t>((u % 32) << 3 | (u % 8));
    bgr.at<cv::Vec3b>(1, u) = cv::Vec3b(c, static_cast<uint8_t>(255 - c), c);
  }
  const UnpackedRgbh back = UnpackRgbh(PackRgbh(bgr, height));
  ASSERT_EQ(back.bgr5.type(), CV_8UC3);
  ASSERT_EQ(back.height_code.type(), CV_16UC1);
  for (int v = 0; v < bgr.rows; ++v) {
    for (int u = 0; u < bgr.cols; ++u) {
      ASSERT_EQ(back.height_code.at<uint16_t>(v, u), height.at<uint16_t>(v, u));
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(back.bgr5.at<cv::Vec3b>(v, u)[c], bgr.at<cv::Vec3b>(v, u)[c] >> 3);
      }
    }
  }
}

TEST(RgbhTest, RejectsBadInputs) {
  cv::Mat bgr(2, 2, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(PackRgbh(bgr, cv::Mat(2, 2, CV_16UC1, cv::Scalar(512))), std::invalid_argument);
  EXPECT_THROW(PackRgbh(bgr, cv::Mat(2, 3, CV_16UC1, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(PackRgbh(bgr, cv::Mat(2, 2, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(UnpackRgbh(cv::Mat(2, 2, CV_8UC1)), std::invalid_argument);
}

TEST(RgbhTest, Expands5BitsToFullRange) {
  EXPECT_EQ(Expand5To8(0), 0);
  EXPECT_EQ(Expand5To8(31), 255);
  EXPECT_EQ(Expand5To8(16), 132);
}

TEST(RgbhTest, PlanarLayouts) {
  // One pixel: R8 = 255 (r5 31), G8 = 128 (g5 16), B8 = 7 (b5 0), height code 511.
  cv::Mat bgr(1, 2, CV_8UC3, cv::Scalar(7, 128, 255));
  cv::Mat height = (cv::Mat_<uint16_t>(1, 2) << 511, 0);
  const cv::Mat packed = PackRgbh(bgr, height);

  const PlanarImage rgbh = RgbhToPlanar(packed, NetworkInput::kRgbh);
  ASSERT_EQ(rgbh.channels, 4);
  ASSERT_EQ(rgbh.data.size(), 8u);
  EXPECT_FLOAT_EQ(rgbh.At(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgbh.At(1, 0, 0), 16.0f / 31);
  EXPECT_FLOAT_EQ(rgbh.At(2, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(rgbh.At(3, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgbh.At(3, 0, 1), 0.0f);  // no stereo

  const PlanarImage fixed = RgbhToPlanar(packed, NetworkInput::kRgbhFixed);
  ASSERT_EQ(fixed.channels, 3);
  EXPECT_FLOAT_EQ(fixed.At(0, 0, 0), 0.299f + 0.587f * 16 / 31);
  EXPECT_FLOAT_EQ(fixed.At(1, 0, 0), 1.0f);  // 0.5 + 0.5 (r - b) with r = 1, b = 0
  EXPECT_FLOAT_EQ(fixed.At(2, 0, 0), 1.0f);

  const PlanarImage rgb = RgbToPlanar(bgr);
  ASSERT_EQ(rgb.channels, 3);
  EXPECT_FLOAT_EQ(rgb.At(0, 0, 1), 1.0f);
  EXPECT_FLOAT_EQ(rgb.At(2, 0, 1), 7.0f / 255);

  DepthQuantization depth;
  cv::Mat depth_code = (cv::Mat_<uint16_t>(1, 2) << 65535, 0);
  const PlanarImage rgbd = RgbdToPlanar(bgr, depth_code, height, depth);
  ASSERT_EQ(rgbd.channels, 5);
  EXPECT_FLOAT_EQ(rgbd.At(1, 0, 0), 128.0f / 255);
  EXPECT_FLOAT_EQ(rgbd.At(3, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgbd.At(3, 0, 1), 0.0f);
  EXPECT_FLOAT_EQ(rgbd.At(4, 0, 0), 1.0f);
  EXPECT_THROW(RgbhToPlanar(packed, NetworkInput::kRgbd), std::invalid_argument);
}

TEST(RgbhTest, NetworkInputNames) {
  for (NetworkInput input :
       {NetworkInput::kRgb, NetworkInput::kRgbh, NetworkInput::kRgbhFixed, NetworkInput::kRgbd}) {
    EXPECT_EQ(ParseNetworkInput(NetworkInputName(input)), input);
  }
  EXPECT_EQ(NetworkInputChannels(NetworkInput::kRgbd), 5);
  EXPECT_EQ(ParseNetworkInput("rgb-h"), std::nullopt);
  EXPECT_EQ(ParseNetworkInput("RGB"), std::nullopt);
}

}  // namespace
}  // namespace stereodet
