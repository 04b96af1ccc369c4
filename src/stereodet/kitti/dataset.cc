#include "stereodet/kitti/dataset.h"

#include <algorithm>
#include <cstring>
#include <system_error>

#include "stereodet/kitti/text_number.h"
#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"
#include "stereodet/util/strings.h"

namespace stereodet {

namespace fs = std::filesystem;

bool IsFrameId(std::string_view text) {
  return !text.empty() &&
         std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
}

namespace {

// Numeric order for digit strings of any length ("999" before "1000"), plain order otherwise.
bool IdLess(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return a.size() < b.size();
  return a < b;
}

// Ids of the files NNNNNN.<extension> in `dir`, sorted; empty if `dir` is not a folder. Hidden
// files (the atomic writer's ".NAME.tmp-*") and other names are ignored.
std::vector<std::string> IdsIn(const fs::path& dir, const std::string& extension) {
  std::vector<std::string> ids;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return ids;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& path = it->path();
    if (path.extension() != extension) continue;
    std::string stem = path.stem().string();
    if (IsFrameId(stem)) ids.push_back(std::move(stem));
  }
  STEREODET_CHECK_IO(!ec) << "cannot list " << dir.string() << ": " << ec.message();
  std::sort(ids.begin(), ids.end(), IdLess);
  return ids;
}

}  // namespace

KittiDataset::KittiDataset(fs::path root, std::string subset)
    : root_(std::move(root)), subset_(std::move(subset)) {
  std::error_code ec;
  STEREODET_CHECK_IO(fs::is_directory(SubsetDir(), ec))
      << SubsetDir().string() << " is not a folder (expected the KITTI object layout ROOT/"
      << subset_ << "/{image_2,label_2,calib,...})";
}

FramePaths KittiDataset::Paths(const std::string& id) const {
  const fs::path dir = SubsetDir();
  FramePaths paths;
  paths.id = id;
  paths.image_left = dir / "image_2" / (id + ".png");
  paths.image_right = dir / "image_3" / (id + ".png");
  paths.label = dir / "label_2" / (id + ".txt");
  paths.calib = dir / "calib" / (id + ".txt");
  paths.velodyne = dir / "velodyne" / (id + ".bin");
  paths.disparity = dir / "disp_noc_0" / (id + ".png");
  paths.planes = dir / "planes" / (id + ".txt");
  return paths;
}

std::vector<std::string> KittiDataset::ListIds() const {
  const fs::path dir = SubsetDir();
  std::vector<std::string> ids = IdsIn(dir / "image_2", ".png");
  if (ids.empty()) ids = IdsIn(dir / "label_2", ".txt");
  // A testing/ set without images has neither; its calib files still name the frames.
  if (ids.empty()) ids = IdsIn(dir / "calib", ".txt");
  return ids;
}

std::vector<std::string> KittiDataset::ReadSplit(const fs::path& split) const {
  fs::path path = split;
  std::error_code ec;
  if (!fs::exists(path, ec) && split.is_relative()) {
    fs::path in_image_sets = root_ / "ImageSets" / split;
    if (!in_image_sets.has_extension()) in_image_sets += ".txt";
    STEREODET_CHECK_IO(fs::exists(in_image_sets, ec))
        << "split file not found: neither " << split.string() << " nor " << in_image_sets.string()
        << " exists";
    path = in_image_sets;
  }
  return ParseSplit(ReadFile(path), path.string());
}

std::vector<std::string> ParseSplit(std::string_view text, const std::string& source) {
  text = StripUtf8Bom(text);
  std::vector<std::string> ids;
  int line_number = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    ++line_number;
    std::string_view line = kitti_internal::NextLine(text, &pos);
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
    while (!line.empty() && (line.back() == ' ' || line.back() == '\t' || line.back() == '\r')) {
      line.remove_suffix(1);
    }
    if (line.empty()) continue;
    if (!IsFrameId(line)) {
      throw ParseError(source, line_number, "frame id",
                       kitti_internal::QuoteToken(line) + " is not a frame id (digits only)");
    }
    ids.emplace_back(line);
  }
  return ids;
}

std::vector<std::string> FindMissingFiles(const KittiDataset& dataset,
                                          const std::vector<std::string>& ids,
                                          const RequiredFiles& required) {
  std::vector<std::string> sorted = ids;
  std::sort(sorted.begin(), sorted.end(), IdLess);
  std::vector<std::string> missing;
  std::error_code ec;
  const fs::path subset_dir = dataset.SubsetDir();
  for (const std::string& id : sorted) {
    const FramePaths paths = dataset.Paths(id);
    auto check = [&](bool needed, const fs::path& path) {
      if (needed && !fs::exists(path, ec)) {
        missing.push_back(id + ": " + path.lexically_relative(subset_dir).generic_string());
      }
    };
    check(required.image_left, paths.image_left);
    check(required.image_right, paths.image_right);
    check(required.label, paths.label);
    check(required.calib, paths.calib);
    check(required.velodyne, paths.velodyne);
  }
  return missing;
}

void CheckRequiredFiles(const KittiDataset& dataset, const std::vector<std::string>& ids,
                        const RequiredFiles& required) {
  const std::vector<std::string> missing = FindMissingFiles(dataset, ids, required);
  if (missing.empty()) return;
  std::string list;
  for (size_t i = 0; i < std::min<size_t>(missing.size(), 5); ++i) list += "\n  " + missing[i];
  STEREODET_THROW_IO() << missing.size() << " required files are missing under "
                       << dataset.SubsetDir().string() << ", e.g." << list;
}

void WriteSplit(const fs::path& path, const std::vector<std::string>& ids) {
  std::string text;
  text.reserve(ids.size() * 7);
  for (const std::string& id : ids) {
    STEREODET_CHECK(IsFrameId(id)) << "cannot write split " << path.string() << ": '" << id
                                   << "' is not a frame id (digits only)";
    text.append(id).push_back('\n');
  }
  WriteFileAtomically(path, text);
}

std::string FrameId(int index) {
  STEREODET_CHECK(index >= 0) << "frame index must be >= 0, got " << index;
  std::string digits = std::to_string(index);
  if (digits.size() < 6) digits.insert(0, 6 - digits.size(), '0');
  return digits;
}

}  // namespace stereodet
