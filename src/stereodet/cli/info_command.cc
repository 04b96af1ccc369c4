// `stereodet info DIR`: what a KITTI-format dataset holds and what is wrong with it.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "stereodet/cli/commands.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/dataset_summary.h"
#include "stereodet/util/check.h"

namespace stereodet::cli {

namespace {

struct InfoArgs {
  std::string root;
  std::string split;
  std::string subset = "training";
  bool json = false;
  DatasetSummaryOptions options;  // --lenient, --distance-bin
};

// Sets below this size finish in a blink; a progress line would only clutter the output.
constexpr size_t kProgressMinFrames = 1000;
// Problems listed in the text output per kind; --json lists them all.
constexpr size_t kMaxListed = 50;

void PrintList(const std::string& title, const std::vector<std::string>& lines) {
  if (lines.empty()) return;
  fmt::print("  {} ({}):\n", title, lines.size());
  for (size_t i = 0; i < lines.size() && i < kMaxListed; ++i) fmt::print("    {}\n", lines[i]);
  if (lines.size() > kMaxListed) {
    fmt::print("    ... and {} more (--json lists all)\n", lines.size() - kMaxListed);
  }
}

void PrintText(const DatasetSummary& s, const std::string& split_path) {
  fmt::print("dataset: {}\n", s.subset_dir);
  fmt::print("frames: {}{}\n", s.frames,
             split_path.empty() ? std::string(" (all)") : fmt::format(" (split {})", split_path));
  fmt::print("labelled frames: {}, objects: {}\n", s.frames_with_labels, s.objects);
  if (!s.classes.empty()) {
    fmt::print("\n{:<16} {:>8} {:>8} {:>9} {:>9} {:>8}\n", "class", "objects", "easy", "moderate",
               "hard", "none");
    std::array<int64_t, kNumDifficultyBuckets> totals{};
    for (const auto& [name, counts] : s.classes) {
      fmt::print("{:<16} {:>8} {:>8} {:>9} {:>9} {:>8}\n", name, counts.objects,
                 counts.by_difficulty[0], counts.by_difficulty[1], counts.by_difficulty[2],
                 counts.by_difficulty[3]);
      for (int i = 0; i < kNumDifficultyBuckets; ++i) totals[i] += counts.by_difficulty[i];
    }
    fmt::print("{:<16} {:>8} {:>8} {:>9} {:>9} {:>8}\n", "total", s.objects, totals[0], totals[1],
               totals[2], totals[3]);
    fmt::print(
        "(KITTI difficulty, exclusive columns: moderate = moderate but not easy, hard = hard but "
        "not moderate, none = below hard or DontCare)\n");
  }
  if (!s.distance_histogram.empty()) {
    fmt::print("\ndistance sqrt(x^2+z^2) of labels with 3D boxes, DontCare excluded:\n");
    const int64_t peak =
        *std::max_element(s.distance_histogram.begin(), s.distance_histogram.end());
    for (size_t i = 0; i < s.distance_histogram.size(); ++i) {
      const int64_t n = s.distance_histogram[i];
      const int bar = peak > 0 ? static_cast<int>((40 * n + peak - 1) / peak) : 0;
      const std::string bin = fmt::format("{:g}-{:g}", static_cast<double>(i) * s.distance_bin_m,
                                          static_cast<double>(i + 1) * s.distance_bin_m);
      fmt::print("  {:>9} m {:>8}{}{}\n", bin, n, bar > 0 ? "  " : "", std::string(bar, '#'));
    }
  }
  if (s.objects_without_3d > 0) {
    fmt::print("objects without 3D box (KITTI's -1 dimensions): {}\n", s.objects_without_3d);
  }
  if (s.frames_with_calib > 0) {
    auto range = [](double lo, double hi, const char* unit, int digits) {
      return lo == hi ? fmt::format("{:.{}f} {}", lo, digits, unit)
                      : fmt::format("{:.{}f}..{:.{}f} {}", lo, digits, hi, digits, unit);
    };
    fmt::print("\ncalibration: {} frames, focal {}, stereo baseline {}\n", s.frames_with_calib,
               range(s.min_focal_px, s.max_focal_px, "px", 2),
               range(s.min_baseline_m, s.max_baseline_m, "m", 4));
  }
  fmt::print("\n");
  if (s.skipped_lines > 0) {
    fmt::print("skipped bad lines (--lenient): {}\n", s.skipped_lines);
    PrintList("skipped lines", s.skipped);
  }
  if (!s.HasProblems()) {
    fmt::print("problems: none\n");
    return;
  }
  std::vector<std::string> frames_missing;
  for (const std::string& line : s.missing_files) {
    const std::string id = line.substr(0, line.find(':'));
    if (frames_missing.empty() || frames_missing.back() != id) frames_missing.push_back(id);
  }
  fmt::print("problems: {}\n", s.missing_files.size() + s.bad_files.size());
  PrintList(fmt::format("missing files, in {} frames", frames_missing.size()), s.missing_files);
  PrintList("bad files", s.bad_files);
}

nlohmann::json ToJson(const DatasetSummary& s, const std::string& split_path) {
  nlohmann::json j;
  j["dataset"] = s.subset_dir;
  j["split"] = split_path.empty() ? nlohmann::json(nullptr) : nlohmann::json(split_path);
  j["frames"] = s.frames;
  j["frames_with_labels"] = s.frames_with_labels;
  j["objects"] = s.objects;
  nlohmann::json classes = nlohmann::json::object();
  for (const auto& [name, counts] : s.classes) {
    nlohmann::json c;
    c["objects"] = counts.objects;
    for (int i = 0; i < kNumDifficultyBuckets; ++i) {
      c["difficulty"][DifficultyBucketName(static_cast<DifficultyBucket>(i))] =
          counts.by_difficulty[i];
    }
    c["distance_histogram"] = counts.distance_histogram;
    classes[name] = c;
  }
  j["classes"] = classes;
  j["distance_bin_m"] = s.distance_bin_m;
  j["distance_histogram"] = s.distance_histogram;
  j["objects_without_3d"] = s.objects_without_3d;
  j["calibration"] = {{"frames", s.frames_with_calib},
                      {"focal_px", {s.min_focal_px, s.max_focal_px}},
                      {"baseline_m", {s.min_baseline_m, s.max_baseline_m}}};
  j["problems"] = {{"missing_files", s.missing_files},
                   {"bad_files", s.bad_files},
                   {"skipped_lines", s.skipped_lines},
                   {"skipped", s.skipped}};
  j["ok"] = !s.HasProblems();
  return j;
}

void RunInfo(const InfoArgs& args) {
  const KittiDataset dataset(args.root, args.subset);
  std::vector<std::string> ids;
  std::string split_path;
  if (!args.split.empty()) {
    ids = dataset.ReadSplit(args.split);
    split_path = args.split;
    STEREODET_CHECK_IO(!ids.empty()) << "split " << args.split << " lists no frames";
  }
  DatasetSummaryOptions options = args.options;
  const size_t frames = ids.empty() ? dataset.ListIds().size() : ids.size();
  if (frames < kProgressMinFrames || args.json) options.progress.stream = nullptr;
  const DatasetSummary summary = SummarizeDataset(dataset, ids, options);
  if (args.json) {
    fmt::print("{}\n", ToJson(summary, split_path).dump(2));
  } else {
    PrintText(summary, split_path);
  }
  std::fflush(stdout);
  if (!options.lenient && summary.HasProblems()) {
    STEREODET_THROW_IO() << summary.missing_files.size() + summary.bad_files.size()
                         << " problems found in " << summary.subset_dir
                         << " (listed above; --lenient skips bad label lines)";
  }
}

}  // namespace

void AddInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand("info", CommandDescription("info"));
  cmd->add_option("DIR", args->root, "dataset root (holds training/, testing/, ImageSets/)")
      ->required();
  cmd->add_option("--split", args->split,
                  "split file (one frame id per line), or a name under DIR/ImageSets such as val");
  cmd->add_option("--subset", args->subset, "training or testing")
      ->check(CLI::IsMember({"training", "testing"}))
      ->capture_default_str();
  cmd->add_flag("--lenient", args->options.lenient,
                "skip and count bad label lines; exit 0 even when problems are found");
  cmd->add_flag("--json", args->json, "print the summary as JSON on stdout");
  cmd->add_option("--distance-bin", args->options.distance_bin_m,
                  "distance histogram bin width, metres")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->callback([args]() { RunInfo(*args); });
}

}  // namespace stereodet::cli
