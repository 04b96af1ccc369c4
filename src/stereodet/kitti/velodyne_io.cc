#include "stereodet/kitti/velodyne_io.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <string_view>

#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

// The on-disk format is little-endian float32; a byte copy is only right on a little-endian host.
static_assert(std::endian::native == std::endian::little,
              "velodyne_io reads KITTI's little-endian floats by copying bytes");

std::vector<VeloPoint> ParseVelodyne(std::string_view bytes, const std::string& source) {
  STEREODET_CHECK_IO(bytes.size() % sizeof(VeloPoint) == 0)
      << source << ": size " << bytes.size()
      << " bytes is not a multiple of 16 (4 float32 a point: x, y, z, reflectance); the file is "
         "truncated or not a KITTI velodyne scan";
  std::vector<VeloPoint> points(bytes.size() / sizeof(VeloPoint));
  if (!points.empty()) std::memcpy(points.data(), bytes.data(), bytes.size());
  // A NaN or inf value is no measurement: a reader that skipped such points would turn a scan of
  // them into an empty one without a word, so the file is refused, naming the first.
  for (size_t i = 0; i < points.size(); ++i) {
    const VeloPoint& p = points[i];
    const float values[4] = {p.x, p.y, p.z, p.reflectance};
    static constexpr const char* kFields[4] = {"x", "y", "z", "reflectance"};
    for (int k = 0; k < 4; ++k) {
      if (!std::isfinite(values[k])) {
        throw ParseError(source, 0, std::string("point ") + std::to_string(i) + " " + kFields[k],
                         "not a finite number (" + std::to_string(values[k]) + ")");
      }
    }
  }
  return points;
}

std::vector<VeloPoint> ReadVelodyne(const std::filesystem::path& path) {
  return ParseVelodyne(ReadFile(path), path.string());
}

void WriteVelodyne(const std::filesystem::path& path, const std::vector<VeloPoint>& points) {
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(points.data()),
                                             points.size() * sizeof(VeloPoint)));
}

}  // namespace stereodet
