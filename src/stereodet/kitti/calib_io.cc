#include "stereodet/kitti/calib_io.h"

#include <fmt/format.h>

#include <array>
#include <cstring>

#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace {

using kitti_internal::NumberStatus;
using kitti_internal::QuoteToken;
using kitti_internal::ReadFiniteDouble;

// The seven matrices of an object-benchmark calib file, in KITTI's order.
enum Key { kP0, kP1, kP2, kP3, kR0Rect, kTrVeloToCam, kTrImuToVelo, kNumKeys };

struct KeyInfo {
  const char* name;   // object-benchmark spelling, used when writing and in errors
  const char* alias;  // tracking-benchmark spelling, or nullptr
  int rows, cols;
};
constexpr std::array<KeyInfo, kNumKeys> kKeys = {{
    {"P0", nullptr, 3, 4},
    {"P1", nullptr, 3, 4},
    {"P2", nullptr, 3, 4},
    {"P3", nullptr, 3, 4},
    {"R0_rect", "R_rect", 3, 3},
    {"Tr_velo_to_cam", "Tr_velo_cam", 3, 4},
    {"Tr_imu_to_velo", "Tr_imu_velo", 3, 4},
}};

int FindKey(std::string_view key) {
  for (int k = 0; k < kNumKeys; ++k) {
    if (key == kKeys[k].name || (kKeys[k].alias != nullptr && key == kKeys[k].alias)) return k;
  }
  return -1;
}

bool IsBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string EntryName(int key, int index) {
  const int cols = kKeys[key].cols;
  return std::string(kKeys[key].name) + "(" + std::to_string(index / cols) + "," +
         std::to_string(index % cols) + ")";
}

}  // namespace

Calibration ParseCalibration(std::string_view text, const std::string& source) {
  // Values land here first and are copied into the Calibration once all keys are known.
  std::array<std::array<double, 12>, kNumKeys> values{};
  std::array<int, kNumKeys> seen_on_line{};  // 0 = not seen
  // A UTF-8 byte-order mark would otherwise make the first key unknown, and skipped.
  text = StripUtf8Bom(text);
  int line_number = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    ++line_number;
    std::string_view line = kitti_internal::NextLine(text, &pos);

    while (!line.empty() && IsBlank(line.front())) line.remove_prefix(1);
    if (line.empty()) continue;

    // The key: up to the first ':' or blank. The object benchmark writes "P0: ...", the tracking
    // benchmark "R_rect ..." without the colon; both are accepted.
    size_t key_end = 0;
    while (key_end < line.size() && line[key_end] != ':' && !IsBlank(line[key_end])) ++key_end;
    const std::string_view key_text = line.substr(0, key_end);
    line.remove_prefix(key_end);
    if (!line.empty() && line.front() == ':') line.remove_prefix(1);
    const int key = FindKey(key_text);
    // Other keys (KITTI raw's "calib_time", extra cameras) are not ours to judge: skip them.
    if (key < 0) continue;
    if (seen_on_line[key] != 0) {
      throw ParseError(source, line_number, kKeys[key].name,
                       "duplicate key (first on line " + std::to_string(seen_on_line[key]) + ")");
    }
    seen_on_line[key] = line_number;

    const int wanted = kKeys[key].rows * kKeys[key].cols;
    int count = 0;
    size_t i = 0;
    while (true) {
      while (i < line.size() && IsBlank(line[i])) ++i;
      if (i == line.size()) break;
      const size_t start = i;
      while (i < line.size() && !IsBlank(line[i])) ++i;
      const std::string_view token = line.substr(start, i - start);
      if (count >= wanted) {
        ++count;
        continue;  // counted for the message below
      }
      const NumberStatus status = ReadFiniteDouble(token, &values[key][count]);
      if (status != NumberStatus::kOk) {
        throw ParseError(source, line_number, EntryName(key, count),
                         QuoteToken(token) + " " + kitti_internal::NumberStatusMessage(status));
      }
      ++count;
    }
    if (count != wanted) {
      throw ParseError(source, line_number, kKeys[key].name,
                       "expected " + std::to_string(wanted) + " numbers (" +
                           std::to_string(kKeys[key].rows) + "x" + std::to_string(kKeys[key].cols) +
                           "), got " + std::to_string(count));
    }
  }

  for (int k = 0; k < kNumKeys; ++k) {
    if (k != kTrImuToVelo && seen_on_line[k] == 0) {
      throw ParseError(source, 0, kKeys[k].name, "missing key");
    }
  }

  Calibration calib;
  for (int camera = 0; camera < 4; ++camera) {
    for (int i = 0; i < 12; ++i) calib.projection[camera](i / 4, i % 4) = values[kP0 + camera][i];
  }
  for (int i = 0; i < 9; ++i) calib.rect_from_cam0(i / 3, i % 3) = values[kR0Rect][i];
  Eigen::Matrix4d velo = Eigen::Matrix4d::Identity();
  for (int i = 0; i < 12; ++i) velo(i / 4, i % 4) = values[kTrVeloToCam][i];
  calib.cam0_from_velo.matrix() = velo;
  if (seen_on_line[kTrImuToVelo] != 0) {
    Eigen::Matrix4d imu = Eigen::Matrix4d::Identity();
    for (int i = 0; i < 12; ++i) imu(i / 4, i % 4) = values[kTrImuToVelo][i];
    calib.velo_from_imu.matrix() = imu;
  }
  return calib;
}

namespace {

// Why the entry is checked: a rotation with a small error is KITTI's own rounding; anything
// further off (an all-zero matrix, a scale) is a broken file, and would make every point NaN.
void CheckRotation(const Eigen::Matrix3d& rotation, const char* key, const std::string& source) {
  const double det = rotation.determinant();
  const double error =
      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(det > 0) || !(error <= 1e-2)) {
    throw ParseError(source, 0, key,
                     fmt::format("not a rotation (det {:g}, max |R^T R - I| {:g}; must be a "
                                 "rotation to 1e-2)",
                                 det, error));
  }
}

}  // namespace

void CheckCalibration(const Calibration& calib, const std::string& source) {
  constexpr double kMinFocalPx = 1, kMaxFocalPx = 1e6;
  for (int camera : {2, 3}) {
    for (int axis : {0, 1}) {
      const double focal_px = calib.projection[camera](axis, axis);
      if (!(focal_px >= kMinFocalPx && focal_px <= kMaxFocalPx)) {
        throw ParseError(source, 0, EntryName(kP0 + camera, axis * 4 + axis),
                         fmt::format("focal length {:g} px is outside [{:g}, {:g}]", focal_px,
                                     kMinFocalPx, kMaxFocalPx));
      }
    }
  }
  constexpr double kMinBaselineM = 1e-3, kMaxBaselineM = 100;
  const double baseline_m = calib.BaselineM();
  if (!(baseline_m >= kMinBaselineM && baseline_m <= kMaxBaselineM)) {
    throw ParseError(source, 0, "P3",
                     fmt::format("stereo baseline {:g} m (camera 3 minus camera 2 along x) is "
                                 "outside [{:g}, {:g}] m: camera 3 must be right of camera 2",
                                 baseline_m, kMinBaselineM, kMaxBaselineM));
  }
  CheckRotation(calib.rect_from_cam0, kKeys[kR0Rect].name, source);
  CheckRotation(calib.cam0_from_velo.linear(), kKeys[kTrVeloToCam].name, source);
}

Calibration ReadCalibration(const std::filesystem::path& path) {
  Calibration calib = ParseCalibration(ReadFile(path), path.string());
  CheckCalibration(calib, path.string());
  return calib;
}

std::string FormatCalibration(const Calibration& calib) {
  std::string text;
  text.reserve(1400);
  auto append_row_major = [&](int key, const auto& matrix) {
    text.append(kKeys[key].name).push_back(':');
    for (int r = 0; r < kKeys[key].rows; ++r) {
      for (int c = 0; c < kKeys[key].cols; ++c) {
        const double value = matrix(r, c);
        STEREODET_CHECK(std::isfinite(value))
            << "cannot write a calibration: " << EntryName(key, r * kKeys[key].cols + c) << " is "
            << value;
        text.push_back(' ');
        kitti_internal::AppendRoundTrip(&text, value, std::chars_format::scientific, 12);
      }
    }
    text.push_back('\n');
  };
  for (int camera = 0; camera < 4; ++camera)
    append_row_major(kP0 + camera, calib.projection[camera]);
  append_row_major(kR0Rect, calib.rect_from_cam0);
  append_row_major(kTrVeloToCam, calib.cam0_from_velo.matrix());
  append_row_major(kTrImuToVelo, calib.velo_from_imu.matrix());
  // KITTI's object-benchmark calib files end with an empty line.
  text.push_back('\n');
  return text;
}

void WriteCalibration(const std::filesystem::path& path, const Calibration& calib) {
  WriteFileAtomically(path, FormatCalibration(calib));
}

}  // namespace stereodet
