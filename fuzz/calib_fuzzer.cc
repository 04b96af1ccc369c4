// libFuzzer target for the KITTI calibration parser (ParseCalibration).
//
// Any input must either parse or throw ParseError; the sanitizers catch memory errors and
// undefined behaviour. What parses must survive a round trip: parse(format(calib)) == calib and
// format(parse(format(calib))) == format(calib).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "stereodet/kitti/calib_io.h"
#include "stereodet/util/check.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "calib_fuzzer: %s\n", what);
  std::abort();
}

bool Same(const stereodet::Calibration& a, const stereodet::Calibration& b) {
  for (int i = 0; i < 4; ++i) {
    if (a.projection[i] != b.projection[i]) return false;
  }
  return a.rect_from_cam0 == b.rect_from_cam0 &&
         a.cam0_from_velo.matrix() == b.cam0_from_velo.matrix() &&
         a.velo_from_imu.matrix() == b.velo_from_imu.matrix();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Calibration calib;
  try {
    calib = ParseCalibration(text, "fuzz.txt");
  } catch (const ParseError& e) {
    if (e.field().empty()) Fail("ParseError without a field");
    return 0;
  }
  const std::string formatted = FormatCalibration(calib);
  const Calibration again = ParseCalibration(formatted, "formatted.txt");  // must not throw
  if (!Same(again, calib)) Fail("parse(format(calib)) != calib");
  if (FormatCalibration(again) != formatted) Fail("format is not stable");
  // Derived quantities must not crash either (they may be meaningless for garbage input).
  (void)calib.RectFromVelo();
  (void)calib.CameraCentreInRect(2);
  return 0;
}
