#include "stereodet/stereo/rgbh.h"

#include <opencv2/core/utility.hpp>

#include "stereodet/util/check.h"

namespace stereodet {
namespace {

void CheckBgr(const cv::Mat& bgr) {
  STEREODET_CHECK(bgr.type() == CV_8UC3) << "expected an 8-bit BGR image, got type " << bgr.type();
}

void CheckCodes(const cv::Mat& codes, const cv::Size& size, const char* what) {
  STEREODET_CHECK(codes.type() == CV_16UC1)
      << what << " codes must be CV_16UC1, got type " << codes.type();
  STEREODET_CHECK(codes.size() == size) << what << " codes and image differ in size";
}

PlanarImage MakePlanar(int channels, const cv::Size& size) {
  PlanarImage planar;
  planar.channels = channels;
  planar.rows = size.height;
  planar.cols = size.width;
  planar.data.resize(static_cast<size_t>(channels) * size.area());
  return planar;
}

}  // namespace

cv::Mat PackRgbh(const cv::Mat& bgr, const cv::Mat& height_code) {
  CheckBgr(bgr);
  CheckCodes(height_code, bgr.size(), "height");
  cv::Mat packed(bgr.size(), CV_8UC3);
  bool code_too_large = false;
  for (int v = 0; v < bgr.rows; ++v) {
    const uint8_t* in = bgr.ptr<uint8_t>(v);
    const uint16_t* h = height_code.ptr<uint16_t>(v);
    uint8_t* out = packed.ptr<uint8_t>(v);
    for (int u = 0; u < bgr.cols; ++u) {
      code_too_large |= h[u] > HeightQuantization::kLevels;
      out[3 * u + 0] = static_cast<uint8_t>((in[3 * u + 0] & 0xF8) | (h[u] & 7));
      out[3 * u + 1] = static_cast<uint8_t>((in[3 * u + 1] & 0xF8) | ((h[u] >> 3) & 7));
      out[3 * u + 2] = static_cast<uint8_t>((in[3 * u + 2] & 0xF8) | ((h[u] >> 6) & 7));
    }
  }
  STEREODET_CHECK(!code_too_large) << "height codes must be 0..511";
  return packed;
}

UnpackedRgbh UnpackRgbh(const cv::Mat& packed) {
  STEREODET_CHECK(packed.type() == CV_8UC3)
      << "an RGB-H image must be 8-bit with 3 channels, got type " << packed.type();
  UnpackedRgbh out{cv::Mat(packed.size(), CV_8UC3), cv::Mat(packed.size(), CV_16UC1)};
  for (int v = 0; v < packed.rows; ++v) {
    const uint8_t* in = packed.ptr<uint8_t>(v);
    uint8_t* colour = out.bgr5.ptr<uint8_t>(v);
    uint16_t* h = out.height_code.ptr<uint16_t>(v);
    for (int u = 0; u < packed.cols; ++u) {
      const uint8_t b = in[3 * u], g = in[3 * u + 1], r = in[3 * u + 2];
      colour[3 * u + 0] = b >> 3;
      colour[3 * u + 1] = g >> 3;
      colour[3 * u + 2] = r >> 3;
      h[u] = static_cast<uint16_t>((r & 7) << 6 | (g & 7) << 3 | (b & 7));
    }
  }
  return out;
}

const char* NetworkInputName(NetworkInput input) {
  switch (input) {
    case NetworkInput::kRgb:
      return "rgb";
    case NetworkInput::kRgbh:
      return "rgbh";
    case NetworkInput::kRgbhFixed:
      return "rgbh-fixed";
    case NetworkInput::kRgbd:
      return "rgbd";
  }
  return "?";
}

std::optional<NetworkInput> ParseNetworkInput(std::string_view text) {
  for (NetworkInput input :
       {NetworkInput::kRgb, NetworkInput::kRgbh, NetworkInput::kRgbhFixed, NetworkInput::kRgbd}) {
    if (text == NetworkInputName(input)) return input;
  }
  return std::nullopt;
}

int NetworkInputChannels(NetworkInput input) {
  switch (input) {
    case NetworkInput::kRgb:
      return 3;
    case NetworkInput::kRgbh:
      return 4;
    case NetworkInput::kRgbhFixed:
      return 3;
    case NetworkInput::kRgbd:
      return 5;
  }
  return 0;
}

PlanarImage RgbhToPlanar(const cv::Mat& packed, NetworkInput layout) {
  STEREODET_CHECK(packed.type() == CV_8UC3)
      << "an RGB-H image must be 8-bit with 3 channels, got type " << packed.type();
  STEREODET_CHECK(layout == NetworkInput::kRgbh || layout == NetworkInput::kRgbhFixed)
      << "RgbhToPlanar makes rgbh or rgbh-fixed, not " << NetworkInputName(layout);
  PlanarImage planar = MakePlanar(NetworkInputChannels(layout), packed.size());
  const size_t plane = static_cast<size_t>(packed.total());
  float* c0 = planar.Channel(0);
  cv::parallel_for_(cv::Range(0, packed.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const uint8_t* in = packed.ptr<uint8_t>(v);
      const size_t row = static_cast<size_t>(v) * packed.cols;
      for (int u = 0; u < packed.cols; ++u) {
        const uint8_t b8 = in[3 * u], g8 = in[3 * u + 1], r8 = in[3 * u + 2];
        const float r = (r8 >> 3) * (1.0f / 31), g = (g8 >> 3) * (1.0f / 31),
                    b = (b8 >> 3) * (1.0f / 31);
        const float h = static_cast<float>((r8 & 7) << 6 | (g8 & 7) << 3 | (b8 & 7)) *
                        (1.0f / HeightQuantization::kLevels);
        const size_t i = row + u;
        if (layout == NetworkInput::kRgbh) {
          c0[i] = r;
          c0[plane + i] = g;
          c0[2 * plane + i] = b;
          c0[3 * plane + i] = h;
        } else {
          c0[i] = kLumaR * r + kLumaG * g + kLumaB * b;
          c0[plane + i] = 0.5f + 0.5f * (r - b);
          c0[2 * plane + i] = h;
        }
      }
    }
  });
  return planar;
}

PlanarImage RgbToPlanar(const cv::Mat& bgr) {
  CheckBgr(bgr);
  PlanarImage planar = MakePlanar(3, bgr.size());
  const size_t plane = static_cast<size_t>(bgr.total());
  float* c0 = planar.Channel(0);
  for (int v = 0; v < bgr.rows; ++v) {
    const uint8_t* in = bgr.ptr<uint8_t>(v);
    const size_t row = static_cast<size_t>(v) * bgr.cols;
    for (int u = 0; u < bgr.cols; ++u) {
      c0[row + u] = in[3 * u + 2] * (1.0f / 255);
      c0[plane + row + u] = in[3 * u + 1] * (1.0f / 255);
      c0[2 * plane + row + u] = in[3 * u] * (1.0f / 255);
    }
  }
  return planar;
}

PlanarImage RgbdToPlanar(const cv::Mat& bgr, const cv::Mat& depth_code, const cv::Mat& height_code,
                         const DepthQuantization& depth) {
  depth.Check();
  CheckBgr(bgr);
  CheckCodes(depth_code, bgr.size(), "depth");
  CheckCodes(height_code, bgr.size(), "height");
  PlanarImage planar = MakePlanar(5, bgr.size());
  const size_t plane = static_cast<size_t>(bgr.total());
  float* c0 = planar.Channel(0);
  const float depth_scale = 1.0f / depth.MaxCode();
  for (int v = 0; v < bgr.rows; ++v) {
    const uint8_t* in = bgr.ptr<uint8_t>(v);
    const uint16_t* z = depth_code.ptr<uint16_t>(v);
    const uint16_t* h = height_code.ptr<uint16_t>(v);
    const size_t row = static_cast<size_t>(v) * bgr.cols;
    for (int u = 0; u < bgr.cols; ++u) {
      c0[row + u] = in[3 * u + 2] * (1.0f / 255);
      c0[plane + row + u] = in[3 * u + 1] * (1.0f / 255);
      c0[2 * plane + row + u] = in[3 * u] * (1.0f / 255);
      c0[3 * plane + row + u] = z[u] * depth_scale;
      c0[4 * plane + row + u] = h[u] * (1.0f / HeightQuantization::kLevels);
    }
  }
  return planar;
}

}  // namespace stereodet
