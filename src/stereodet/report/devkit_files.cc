#include "stereodet/report/devkit_files.h"

#include <cctype>
#include <cstdio>
#include <map>
#include <string>
#include <tuple>
#include <utility>

#include "stereodet/util/atomic_file.h"
#include "stereodet/util/check.h"

namespace stereodet {
namespace fs = std::filesystem;

namespace {

// printf's "%f" of the devkit, so that NaN and infinities read as the devkit writes them.
std::string PrintfF(double value) {
  char text[512];
  std::snprintf(text, sizeof(text), "%f", value);
  return text;
}

// The devkit's file stem of a kind: detection, detection_ground, detection_3d.
const char* KindStem(OverlapKind kind) {
  switch (kind) {
    case OverlapKind::k2D:
      return "detection";
    case OverlapKind::kBev:
      return "detection_ground";
    case OverlapKind::k3D:
      return "detection_3d";
    case OverlapKind::kLetBev:  // the devkit has no LET: WriteDevkitFiles skips those cells
    case OverlapKind::kLet3D:
      break;
  }
  return "detection";
}

std::string Lower(const std::string& text) {
  std::string out = text;
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// saveStats: a line of "%f " per difficulty.
std::string StatsText(const std::vector<const std::vector<double>*>& slots) {
  std::string text;
  for (const std::vector<double>* line : slots) {
    for (const double v : *line) {
      text += PrintfF(v);
      text += ' ';
    }
    text += "\n";
  }
  return text;
}

// saveAndPlotPlots' data file: recall i/40 and the three difficulties' slot i.
std::string PlotText(const std::vector<const std::vector<double>*>& slots) {
  constexpr int kSlots = 41;
  std::string text;
  for (int i = 0; i < kSlots; ++i) {
    text += PrintfF(static_cast<double>(i) / (kSlots - 1.0));
    for (const std::vector<double>* line : slots) {
      text += ' ';
      text += PrintfF(line->at(i));
    }
    text += "\n";
  }
  return text;
}

}  // namespace

std::vector<fs::path> WriteDevkitFiles(const fs::path& dir, const EvalResult& result) {
  // The cells by class and kind, Easy / Moderate / Hard, in the result's order.
  std::vector<std::pair<std::string, OverlapKind>> order;
  std::map<std::pair<std::string, OverlapKind>, std::map<Difficulty, const ClassResult*>> cells;
  for (const ClassResult& r : result.results) {
    if (!r.evaluated || IsLetKind(r.metric)) continue;
    STEREODET_CHECK(r.kitti_precision.size() == 41)
        << "--devkit-files: the devkit's files hold its 41 precision slots, which only the KITTI "
           "matcher computes ("
        << r.class_name << " has none: evaluate with --matcher kitti)";
    const auto key = std::make_pair(r.class_name, r.metric);
    if (cells.count(key) == 0) order.push_back(key);
    cells[key][r.difficulty] = &r;
  }
  std::vector<fs::path> written;
  for (const auto& key : order) {
    const auto& by_difficulty = cells[key];
    if (by_difficulty.size() != 3) continue;  // the devkit writes the three difficulties or none
    std::vector<const std::vector<double>*> precision, aos;
    bool has_aos = key.second == OverlapKind::k2D;
    for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
      const ClassResult& r = *by_difficulty.at(d);
      precision.push_back(&r.kitti_precision);
      aos.push_back(&r.kitti_aos);
      has_aos = has_aos && r.has_aos && r.kitti_aos.size() == 41;
    }
    const std::string name = Lower(key.first);
    const std::string stem = KindStem(key.second);
    auto write = [&](const fs::path& path, const std::string& text) {
      WriteFileAtomically(path, text);
      written.push_back(path);
    };
    write(dir / ("stats_" + name + "_" + stem + ".txt"), StatsText(precision));
    if (has_aos) write(dir / ("stats_" + name + "_orientation.txt"), StatsText(aos));
    write(dir / "plot" / (name + "_" + stem + ".txt"), PlotText(precision));
    if (has_aos) write(dir / "plot" / (name + "_orientation.txt"), PlotText(aos));
  }
  STEREODET_CHECK(!written.empty())
      << "--devkit-files: no class and overlap kind was evaluated at Easy, Moderate and Hard, and "
         "the devkit writes its files for all three (evaluate every difficulty)";
  return written;
}

}  // namespace stereodet
