// The detector's input encodings (the paper's "RGB" and "RGB-H") and the conversion of an image and
// its stereo height codes into the planar floats the network reads. The encoders themselves are the
// stereo module's (stereo/rgbh.h); this file picks one per model. All three feed the identical
// backbone: rgb and rgbh-fixed give it three channels directly; rgbh-learned gives four (5-bit R,
// G, B and the 9-bit height) and the network's first layer, a learned 1x1 convolution, compresses
// R, G, B to two channels, so the backbone again sees three.
#ifndef STEREODET_MODELS_SSD_INPUT_ENCODING_H_
#define STEREODET_MODELS_SSD_INPUT_ENCODING_H_

#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "stereodet/stereo/rgbh.h"

namespace stereodet {

enum class InputEncoding {
  kRgb,        // 8-bit colour: R, G, B (the baseline)
  kRgbhFixed,  // 5-bit colour compressed to 2 channels by a fixed weighting (Y, C), + 9-bit height
  kRgbhLearned,  // 5-bit R, G, B + 9-bit height; a learned 1x1 conv compresses R, G, B to 2
                 // channels
};

const char* InputEncodingName(InputEncoding encoding);  // "rgb", "rgbh-fixed", "rgbh-learned"
std::optional<InputEncoding> ParseInputEncoding(std::string_view text);

// The stereo module's planar layout each encoding uses: kRgb, kRgbhFixed, kRgbh.
NetworkInput NetworkLayout(InputEncoding encoding);
// Channels of the network's input tensor: 3, 3, 4.
int NetworkInputChannels(InputEncoding encoding);
// Channels the backbone sees, after the learned compression: always 3.
inline constexpr int kBackboneInputChannels = 3;
// Whether the encoding needs a stereo height image.
bool UsesHeight(InputEncoding encoding);

// Builds the network input. `bgr` is CV_8UC3 (OpenCV's BGR order); `height_code` is CV_16UC1 with
// 9-bit height codes 1..511 and 0 where stereo gave nothing (stereo/reprojection.h,
// QuantizeHeight); it is ignored (may be empty) for kRgb. Both must have the same size: the
// network's input size. Returns NetworkInputChannels(encoding) planes, every value in [0, 1],
// channels in this order:
//   rgb:          R / 255, G / 255, B / 255
//   rgbh-fixed:   Y, C of the 5-bit colour (stereo/rgbh.h), code / 511
//   rgbh-learned: (R >> 3) / 31, (G >> 3) / 31, (B >> 3) / 31, code / 511
PlanarImage EncodeNetworkInput(const cv::Mat& bgr, const cv::Mat& height_code,
                               InputEncoding encoding);

}  // namespace stereodet

#endif  // STEREODET_MODELS_SSD_INPUT_ENCODING_H_
