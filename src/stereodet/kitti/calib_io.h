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
// without the colon; other keys (KITTI raw's "calib_time") and blank lines are ignored.
Calibration ParseCalibration(std::string_view text, const std::string& source);
Calibration ReadCalibration(const std::filesystem::path& path);

// KITTI's own layout: "KEY: v v v ..." with each value as "%.12e" when that reads back exactly,
// otherwise the shortest exact text; all seven keys, then an empty line, as KITTI's files end.
// Throws std::invalid_argument for a NaN or infinite entry.
std::string FormatCalibration(const Calibration& calib);
void WriteCalibration(const std::filesystem::path& path, const Calibration& calib);  // atomic

}  // namespace stereodet

#endif  // STEREODET_KITTI_CALIB_IO_H_
