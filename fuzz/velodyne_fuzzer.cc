// libFuzzer target for the velodyne scan reader (ParseVelodyne).
//
// Any input must either parse (its size a multiple of 16, every value finite) or throw
// std::runtime_error (a NaN or inf value is refused, naming the point and field); what parses
// holds exactly the input's bytes, 16 a point.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "stereodet/kitti/velodyne_io.h"

namespace {

void Fail(const char* what) {
  std::fprintf(stderr, "velodyne_fuzzer: %s\n", what);
  std::abort();
}

// True when each of the whole floats in the first size - size % 4 bytes is finite.
bool AllFinite(const uint8_t* data, size_t size) {
  for (size_t at = 0; at + 4 <= size; at += 4) {
    float value;
    std::memcpy(&value, data + at, 4);
    if (!std::isfinite(value)) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace stereodet;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  std::vector<VeloPoint> points;
  try {
    points = ParseVelodyne(bytes, "fuzz.bin");
  } catch (const std::runtime_error&) {
    if (size % 16 == 0 && AllFinite(data, size))
      Fail("a whole number of finite points was refused");
    return 0;
  }
  if (size % 16 != 0) Fail("a partial point was accepted");
  if (!AllFinite(data, size)) Fail("a NaN or inf value was accepted");
  if (points.size() != size / 16) Fail("wrong point count");
  if (size > 0 && std::memcmp(points.data(), data, size) != 0) Fail("the bytes changed");
  return 0;
}
