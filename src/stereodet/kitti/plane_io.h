// Reading and writing ground-plane files, the layout that KITTI tools (AVOD, MV3D and others)
// keep next to the object benchmark as ROOT/training/planes/NNNNNN.txt:
//   # Plane
//   Width 4
//   Height 1
//   a b c d
// The plane a x + b y + c z + d = 0 is in the rectified camera frame (metres); its normal
// (a, b, c) points up, so b is near -1 and d is about the camera's height above the road.
// `stereodet synth` writes the true ground of each frame in it.
#ifndef STEREODET_KITTI_PLANE_IO_H_
#define STEREODET_KITTI_PLANE_IO_H_

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>

namespace stereodet {

// Parses a plane file's text; `source` names it in errors. Throws ParseError naming the line for a
// missing header line or a fourth line that is not four finite numbers, and for a normal (a, b, c)
// whose length is not 1 to within 1e-3. Returns (a, b, c, d).
Eigen::Vector4d ParseGroundPlane(std::string_view text, const std::string& source);
Eigen::Vector4d ReadGroundPlane(const std::filesystem::path& path);

// The text above, each number as "%.6e". Throws std::invalid_argument for a normal that is not
// unit length (to 1e-3) or a non-finite entry.
std::string FormatGroundPlane(const Eigen::Vector4d& plane);
void WriteGroundPlane(const std::filesystem::path& path, const Eigen::Vector4d& plane);  // atomic

}  // namespace stereodet

#endif  // STEREODET_KITTI_PLANE_IO_H_
