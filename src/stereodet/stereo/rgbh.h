// Network inputs built from the left image and the stereo height/depth codes.
//
// RGB-H (the paper's single-shot input): each 8-bit colour channel keeps its 5 high bits and the
// 9-bit height code (reprojection.h, HeightQuantization: 0 = no stereo, 1..511) takes the 9 freed
// bits, so a pixel still fits in 24 bits and an RGB-H PNG is the size of an RGB PNG. Bit layout of
// the packed CV_8UC3 image (OpenCV's B, G, R channel order, as written to and read from PNG files):
//
//   channel R:  r4 r3 r2 r1 r0 h8 h7 h6      (colour in bits 7..3, height bits 8..6 in bits 2..0)
//   channel G:  g4 g3 g2 g1 g0 h5 h4 h3
//   channel B:  b4 b3 b2 b1 b0 h2 h1 h0
//
// where r4..r0 = R8 >> 3 (truncation). So the packed file, viewed as an ordinary image, is the
// picture with 3 bits of noise per channel, and unpacking is lossless for 5-bit colour and 9-bit
// height.
//
// Float conversions for the network return planar CHW float arrays (models converts them to
// tensors), channels in the order documented on each layout.
#ifndef STEREODET_STEREO_RGBH_H_
#define STEREODET_STEREO_RGBH_H_

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "stereodet/stereo/reprojection.h"

namespace stereodet {

// Packs an 8-bit BGR image (CV_8UC3) and a height-code image (CV_16UC1, 0..511) of the same size.
// Throws std::invalid_argument on a type or size mismatch or a code above 511.
cv::Mat PackRgbh(const cv::Mat& bgr, const cv::Mat& height_code);

struct UnpackedRgbh {
  cv::Mat bgr5;         // CV_8UC3, 5-bit colour values 0..31 (B, G, R)
  cv::Mat height_code;  // CV_16UC1, 0..511 (0 = no stereo)
};
// Exact inverse of PackRgbh on the 5-bit colour and the height code. Requires CV_8UC3.
UnpackedRgbh UnpackRgbh(const cv::Mat& packed);

// 5-bit colour back to 8 bits by bit replication (31 -> 255, 0 -> 0): c8 = c5 << 3 | c5 >> 2.
inline uint8_t Expand5To8(uint8_t c5) { return static_cast<uint8_t>(c5 << 3 | c5 >> 2); }

// A planar float image: data[(c * rows + v) * cols + u], channels in the documented order.
struct PlanarImage {
  int channels = 0, rows = 0, cols = 0;
  std::vector<float> data;
  float At(int c, int v, int u) const {
    return data[(static_cast<size_t>(c) * rows + v) * cols + u];
  }
  float* Channel(int c) { return data.data() + static_cast<size_t>(c) * rows * cols; }
};

// The inputs a detector can be trained on.
enum class NetworkInput {
  kRgb,   // 3 channels: R, G, B = 8-bit / 255 (the image-only baseline)
  kRgbh,  // 4 channels: R5/31, G5/31, B5/31, H/511 (for a learned 1x1 compression, the paper's)
  kRgbhFixed,  // 3 channels: Y, C, H/511 with the fixed colour conversion of 5-bit colour below
  kRgbd,       // 5 channels: R, G, B (8-bit / 255), depth code / max code, H/511 (late fusion)
};
const char* NetworkInputName(NetworkInput input);  // "rgb", "rgbh", "rgbh-fixed", "rgbd"
std::optional<NetworkInput> ParseNetworkInput(std::string_view text);
int NetworkInputChannels(NetworkInput input);

// The fixed two-channel colour compression of kRgbhFixed, on r, g, b = 5-bit values / 31 in [0, 1]:
//   Y = 0.299 r + 0.587 g + 0.114 b        (ITU-R BT.601 luma, OpenCV's BGR2GRAY/YCrCb weights)
//   C = 0.5 + 0.5 (r - b)                  (red-blue opponent chroma, in [0, 1])
// Green is carried by Y only, as in a Bayer pattern where it dominates luminance.
inline constexpr float kLumaR = 0.299f, kLumaG = 0.587f, kLumaB = 0.114f;

// From a packed RGB-H image: kRgbh (4 channels) or kRgbhFixed (3 channels).
PlanarImage RgbhToPlanar(const cv::Mat& packed, NetworkInput layout = NetworkInput::kRgbh);
// From an 8-bit BGR image: kRgb.
PlanarImage RgbToPlanar(const cv::Mat& bgr);
// kRgbd from an 8-bit BGR image, a depth-code image (CV_16UC1 from `depth`) and a height-code
// image. The depth channel is code / MaxCode (0 = no stereo, ~0 = near, 1 = max_m and beyond).
PlanarImage RgbdToPlanar(const cv::Mat& bgr, const cv::Mat& depth_code, const cv::Mat& height_code,
                         const DepthQuantization& depth);

}  // namespace stereodet

#endif  // STEREODET_STEREO_RGBH_H_
