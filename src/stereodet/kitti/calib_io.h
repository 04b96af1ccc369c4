// Reading and writing KITTI object-benchmark calibration files:
//   P0: 12 numbers   P1   P2   P3   R0_rect: 9 numbers   Tr_velo_to_cam: 12   Tr_imu_to_velo: 12
// (The tracking benchmark's spellings "R_rect", "Tr_velo_cam" and "Tr_imu_velo" are accepted too.)
#ifndef STEREODET_KITTI_CALIB_IO_H_
#define STEREODET_KITTI_CALIB_IO_H_

#include <filesystem>
#include <string>
#include <string_view>

#include "stereodet/geometry/calibration.h"

namespace stereodet {

// Parses a calibration file's text. `source` names the file in errors. P0..P3, R0_rect and
// Tr_velo_to_cam are required; Tr_imu_to_velo is optional (identity if absent). Throws ParseError
// naming the line and key for a missing key (line 0), a wrong number count, a non-number, NaN or
// infinity (field "P2(1,3)": key, row, column), or a duplicate key. Keys may be written with or
// without the colon; other keys (KITTI raw's "calib_time"), blank lines and a UTF-8 byte-order mark
// at the start of the text are ignored.
Calibration ParseCalibration(std::string_view text, const std::string& source);

// Throws ParseError naming `source` and the field when the calibration cannot describe KITTI's
// rectified stereo pair, so that nothing downstream turns it into NaN or empty point clouds:
//  - P2 and P3: focal lengths fx = P(0,0) and fy = P(1,1) in [1, 1e6] px;
//  - the baseline (camera 3's centre minus camera 2's, along rect x) in [1e-3, 100] m: camera 3
//    is right of camera 2, as in KITTI;
//  - R0_rect and the rotation of Tr_velo_to_cam: rotations to 1e-2 (every entry of R^T R - I within
//    1e-2, det > 0); KITTI's are rotations to about 1e-6.
// P0, P1 and Tr_imu_to_velo are not used by stereodet and are not checked.
void CheckCalibration(const Calibration& calib, const std::string& source);

// ParseCalibration, then CheckCalibration; errors name the file.
Calibration ReadCalibration(const std::filesystem::path& path);

// KITTI's own layout: "KEY: v v v ..." with each value as "%.12e" when that reads back exactly,
// otherwise the shortest exact text; all seven keys, then an empty line, as KITTI's files end.
// Throws std::invalid_argument for a NaN or infinite entry.
std::string FormatCalibration(const Calibration& calib);
void WriteCalibration(const std::filesystem::path& path, const Calibration& calib);  // atomic

}  // namespace stereodet

#endif  // STEREODET_KITTI_CALIB_IO_H_
