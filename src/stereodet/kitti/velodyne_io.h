// KITTI velodyne scans: a flat array of float32 (x, y, z, reflectance), little endian, velo frame.
#ifndef STEREODET_KITTI_VELODYNE_IO_H_
#define STEREODET_KITTI_VELODYNE_IO_H_

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace stereodet {

struct VeloPoint {
  float x = 0, y = 0, z = 0;  // velo frame, metres
  float reflectance = 0;      // [0, 1]
  bool operator==(const VeloPoint&) const = default;
};
static_assert(sizeof(VeloPoint) == 16, "VeloPoint must match KITTI's on-disk layout");

// The points of a velodyne file's bytes (little-endian float32 x, y, z, reflectance a point).
// Throws std::runtime_error naming `source` when the size is not a multiple of 16 bytes, and
// ParseError naming the point (0-based) and field when a value is NaN or inf.
std::vector<VeloPoint> ParseVelodyne(std::string_view bytes, const std::string& source);
// Throws std::runtime_error naming the file if it cannot be read, its size is not a multiple of
// 16 bytes or a value is not finite.
std::vector<VeloPoint> ReadVelodyne(const std::filesystem::path& path);
// Writes atomically.
void WriteVelodyne(const std::filesystem::path& path, const std::vector<VeloPoint>& points);

}  // namespace stereodet

#endif  // STEREODET_KITTI_VELODYNE_IO_H_
