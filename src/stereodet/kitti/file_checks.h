// Cheap checks of a dataset's binary files that need no decoding (the front end `stereodet info`
// links no image library): enough to catch zero-byte, truncated and misnamed files. Each reads at
// most 45 bytes of the file, whatever its size.
#ifndef STEREODET_KITTI_FILE_CHECKS_H_
#define STEREODET_KITTI_FILE_CHECKS_H_

#include <filesystem>

namespace stereodet {

// Throws std::runtime_error naming `path` and what is wrong unless it is a regular file that starts
// with PNG's 8-byte signature and an IHDR chunk (width and height in 1..2^31-1) and ends with the
// IEND chunk (its last 12 bytes, as every complete PNG does). A PNG damaged inside its image data
// passes: finding that needs decoding.
void CheckPngFile(const std::filesystem::path& path);

// Throws std::runtime_error naming `path` unless it is a regular file whose size is a multiple of
// 16 bytes (KITTI's float32 x, y, z, reflectance per point).
void CheckVelodyneFile(const std::filesystem::path& path);

}  // namespace stereodet

#endif  // STEREODET_KITTI_FILE_CHECKS_H_
