// libFuzzer target for the KITTI disparity PNG reader (DecodeKittiDisparity; OpenCV decodes the
// PNG, this code checks its type and converts it).
//
// Any input must either decode or throw std::runtime_error; what decodes is CV_32FC1 with every
// value a valid disparity in (0, 256) px or the invalid marker.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string_view>

#include "stereodet/stereo/disparity.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "disparity_fuzzer: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  cv::setNumThreads(1);
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  cv::Mat disparity;
  try {
    disparity = DecodeKittiDisparity(bytes, "fuzz.png");
  } catch (const std::runtime_error&) {
    return 0;
  }
  if (disparity.type() != CV_32FC1 || disparity.empty()) Fail("not a CV_32FC1 image");
  for (int v = 0; v < disparity.rows; ++v) {
    for (int u = 0; u < disparity.cols; ++u) {
      const float d = disparity.at<float>(v, u);
      if (IsValidDisparity(d) && !(d > 0.0f && d < 256.0f)) Fail("a disparity out of range");
    }
  }
  return 0;
}
