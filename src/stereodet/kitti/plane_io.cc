#include "stereodet/kitti/plane_io.h"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <vector>

#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

constexpr double kUnitTolerance = 1e-3;

std::vector<std::string_view> Lines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
    if (j > i) tokens.push_back(line.substr(i, j - i));
    i = j;
  }
  return tokens;
}

}  // namespace

Eigen::Vector4d ParseGroundPlane(std::string_view text, const std::string& source) {
  const std::vector<std::string_view> lines = Lines(text);
  const char* const kHeader[3] = {"# Plane", "Width 4", "Height 1"};
  for (int i = 0; i < 3; ++i) {
    const std::vector<std::string_view> got =
        i < static_cast<int>(lines.size()) ? Tokens(lines[i]) : std::vector<std::string_view>{};
    const std::vector<std::string_view> want = Tokens(kHeader[i]);
    // The header's words, in either case (some tools write "WIDTH 4").
    bool same = got.size() == want.size();
    for (size_t k = 0; same && k < got.size(); ++k) {
      same = got[k].size() == want[k].size();
      for (size_t c = 0; same && c < got[k].size(); ++c) {
        same = std::tolower(static_cast<unsigned char>(got[k][c])) ==
               std::tolower(static_cast<unsigned char>(want[k][c]));
      }
    }
    if (!same) throw ParseError(source, i + 1, "header", fmt::format("expected '{}'", kHeader[i]));
  }
  if (lines.size() < 4) throw ParseError(source, 4, "plane", "missing the line a b c d");
  const std::vector<std::string_view> tokens = Tokens(lines[3]);
  if (tokens.size() != 4) {
    throw ParseError(source, 4, "plane", fmt::format("expected 4 numbers, got {}", tokens.size()));
  }
  Eigen::Vector4d plane;
  for (int k = 0; k < 4; ++k) {
    if (kitti_internal::ReadFiniteDouble(tokens[k], &plane[k]) !=
        kitti_internal::NumberStatus::kOk) {
      throw ParseError(source, 4, fmt::format("plane[{}]", k),
                       fmt::format("'{}' is not a finite number", tokens[k]));
    }
  }
  const double norm = plane.head<3>().norm();
  if (std::abs(norm - 1.0) > kUnitTolerance) {
    throw ParseError(source, 4, "plane",
                     fmt::format("the normal (a, b, c) has length {}, not 1", norm));
  }
  return plane;
}

Eigen::Vector4d ReadGroundPlane(const std::filesystem::path& path) {
  return ParseGroundPlane(ReadFile(path), path.string());
}

std::string FormatGroundPlane(const Eigen::Vector4d& plane) {
  STEREODET_CHECK(plane.allFinite()) << "ground plane: non-finite entry";
  STEREODET_CHECK(std::abs(plane.head<3>().norm() - 1.0) <= kUnitTolerance)
      << "ground plane: the normal has length " << plane.head<3>().norm() << ", not 1";
  return fmt::format("# Plane\nWidth 4\nHeight 1\n{:.6e} {:.6e} {:.6e} {:.6e}\n", plane[0],
                     plane[1], plane[2], plane[3]);
}

void WriteGroundPlane(const std::filesystem::path& path, const Eigen::Vector4d& plane) {
  WriteFileAtomically(path, FormatGroundPlane(plane));
}

}  // namespace stereodet
