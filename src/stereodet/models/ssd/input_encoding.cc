#include "stereodet/models/ssd/input_encoding.h"

#include "stereodet/util/check.h"

namespace stereodet {

const char* InputEncodingName(InputEncoding encoding) {
  switch (encoding) {
    case InputEncoding::kRgb:
      return "rgb";
    case InputEncoding::kRgbhFixed:
      return "rgbh-fixed";
    case InputEncoding::kRgbhLearned:
      return "rgbh-learned";
  }
  return "unknown";
}

std::optional<InputEncoding> ParseInputEncoding(std::string_view text) {
  for (InputEncoding e :
       {InputEncoding::kRgb, InputEncoding::kRgbhFixed, InputEncoding::kRgbhLearned}) {
    if (text == InputEncodingName(e)) return e;
  }
  return std::nullopt;
}

NetworkInput NetworkLayout(InputEncoding encoding) {
  switch (encoding) {
    case InputEncoding::kRgb:
      return NetworkInput::kRgb;
    case InputEncoding::kRgbhFixed:
      return NetworkInput::kRgbhFixed;
    case InputEncoding::kRgbhLearned:
      return NetworkInput::kRgbh;
  }
  return NetworkInput::kRgb;
}

int NetworkInputChannels(InputEncoding encoding) {
  return NetworkInputChannels(NetworkLayout(encoding));
}

bool UsesHeight(InputEncoding encoding) { return encoding != InputEncoding::kRgb; }

PlanarImage EncodeNetworkInput(const cv::Mat& bgr, const cv::Mat& height_code,
                               InputEncoding encoding) {
  if (encoding == InputEncoding::kRgb) return RgbToPlanar(bgr);
  STEREODET_CHECK(!height_code.empty()) << InputEncodingName(encoding) << " needs a height image";
  // Packing then unpacking is exact for 5-bit colour and 9-bit height, and keeps one definition of
  // the encodings (the stereo module's).
  return RgbhToPlanar(PackRgbh(bgr, height_code), NetworkLayout(encoding));
}

}  // namespace stereodet
