// Writes a RandomFrames data set (src/stereodet/eval/random_frames.h) as KITTI-format folders, for
// comparisons with KITTI's official devkit and for the speed benchmark
// (benchmarks/devkit_speed.sh):
//   OUT/label_2/NNNNNN.txt   labels, 15 fields
//   OUT/det/NNNNNN.txt       detections, 16 fields
// and with --devkit, the layout the official devkit (devkit_object, cpp/evaluate_object.cpp) reads
// from its working folder, which always covers frames 000000..007517 (N_TESTIMAGES):
//   OUT/devkit/data/object/label_2/NNNNNN.txt    hard links to OUT/label_2, then empty files
//   OUT/devkit/results/stereodet/data/NNNNNN.txt hard links to OUT/det, then empty files
// An empty label file with an empty detection file adds nothing to any of the devkit's counts.
// Every number is rounded to --decimals (2, as KITTI writes them; so 2D heights of exactly 25.00 or
// 40.00 px occur now and then); scores to --score-decimals (0 = as generated).
//
//   write_eval_set --out DIR [--frames 3769] [--seed 1] [--fp-per-frame 2] [--labels-per-frame 4.8]
//                  [--duplicates 0.3] [--crowded] [--score-decimals 0] [--decimals 2]
//                  [--snap-heights 0] [--self] [--devkit]
// --snap-heights P makes, with probability P, a label's 2D box exactly 25 or 40 px tall (bottom =
// top
// + 25 / 40) and, independently, a detection's 25, 40, 24.99 or 39.99 px: KITTI's minimum heights,
// where the official devkit's `<=` (labels) and `<` (detections) decide.
// --self writes each label (DontCare rows excepted) as a detection of score 1 instead.
#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "stereodet/eval/random_frames.h"
#include "stereodet/kitti/dataset.h"
#include "stereodet/kitti/label_io.h"

namespace {

namespace fs = std::filesystem;
using stereodet::Object;

// The devkit's N_TESTIMAGES: it reads frames 000000 to 007517, all of which must exist.
constexpr int kDevkitFrames = 7518;

double Round(double v, int decimals) {
  if (decimals <= 0) return v;
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

void RoundObject(Object* o, int decimals) {
  o->truncated = Round(o->truncated, decimals);
  o->alpha = Round(o->alpha, decimals);
  o->box.left = Round(o->box.left, decimals);
  o->box.top = Round(o->box.top, decimals);
  o->box.right = Round(o->box.right, decimals);
  o->box.bottom = Round(o->box.bottom, decimals);
  o->box3d.h = Round(o->box3d.h, decimals);
  o->box3d.w = Round(o->box3d.w, decimals);
  o->box3d.l = Round(o->box3d.l, decimals);
  o->box3d.location = {Round(o->box3d.location.x(), decimals),
                       Round(o->box3d.location.y(), decimals),
                       Round(o->box3d.location.z(), decimals)};
  o->box3d.rotation_y = Round(o->box3d.rotation_y, decimals);
}

// Hard-links `from` to `to` (a copy where links are not possible), or writes an empty `to`.
void LinkOrEmpty(const fs::path& from, const fs::path& to) {
  if (fs::exists(from)) {
    std::error_code ec;
    fs::create_hard_link(from, to, ec);
    if (ec) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
  } else {
    stereodet::WriteObjects(to, {});
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes a random KITTI-like evaluation set (labels and detections)"};
  std::string out;
  stereodet::RandomFramesOptions ro;
  ro.num_frames = 3769;
  int decimals = 2;
  bool self = false, devkit = false;
  double snap = 0.0;
  app.add_option("--out", out, "output folder (label_2/, det/, devkit/)")->required();
  app.add_option("--frames", ro.num_frames, "frames")->capture_default_str();
  app.add_option("--seed", ro.seed, "random seed")->capture_default_str();
  app.add_option("--fp-per-frame", ro.false_positives_per_frame, "mean false positives per frame")
      ->capture_default_str();
  app.add_option("--labels-per-frame", ro.labels_per_frame, "mean labels per frame")
      ->capture_default_str();
  app.add_option("--duplicates", ro.duplicate_probability, "probability of a second detection")
      ->capture_default_str();
  app.add_flag("--crowded", ro.crowded, "small, dense scenes");
  app.add_option("--score-decimals", ro.score_decimals, "score decimals (0 = full precision)")
      ->capture_default_str();
  app.add_option("--decimals", decimals, "decimals of every other number (0 = full precision)")
      ->capture_default_str();
  app.add_option("--snap-heights", snap, "probability of a box exactly at a minimum height")
      ->capture_default_str();
  app.add_flag("--self", self, "detections = the labels (DontCare excepted), score 1");
  app.add_flag("--devkit", devkit, "also write the official devkit's layout under OUT/devkit");
  CLI11_PARSE(app, argc, argv);
  try {
    if (devkit && ro.num_frames > kDevkitFrames) {
      std::cerr << "write_eval_set: --devkit takes at most " << kDevkitFrames << " frames\n";
      return 1;
    }
    std::vector<stereodet::EvalFrame> frames = stereodet::RandomFrames(ro);
    const fs::path root(out);
    fs::create_directories(root / "label_2");
    fs::create_directories(root / "det");
    size_t num_labels = 0, num_dets = 0;
    std::mt19937_64 snap_rng(ro.seed ^ 0x5eed5eedULL);  // RandomFrames' own draws stay the same
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    auto snap_height = [&](Object* o, const std::vector<double>& heights) {
      if (snap <= 0 || o->IsDontCare() || !(uniform(snap_rng) < snap)) return;
      const double h = heights[static_cast<size_t>(uniform(snap_rng) * heights.size())];
      o->box.bottom = Round(o->box.top + h, decimals);
    };
    for (stereodet::EvalFrame& f : frames) {
      for (Object& o : f.labels) {
        RoundObject(&o, decimals);
        snap_height(&o, {25.0, 40.0});
      }
      if (self) {
        f.detections.clear();
        for (const Object& l : f.labels) {
          if (l.IsDontCare()) continue;
          Object d = l;
          d.score = 1.0;
          f.detections.push_back(d);
        }
      } else {
        for (Object& o : f.detections) {
          RoundObject(&o, decimals);
          snap_height(&o, {25.0, 40.0, 24.99, 39.99});
        }
      }
      num_labels += f.labels.size();
      num_dets += f.detections.size();
      stereodet::WriteObjects(root / "label_2" / (f.id + ".txt"), f.labels);
      stereodet::WriteObjects(root / "det" / (f.id + ".txt"), f.detections);
    }
    if (devkit) {
      const fs::path labels = root / "devkit/data/object/label_2";
      const fs::path dets = root / "devkit/results/stereodet/data";
      fs::remove_all(root / "devkit");
      fs::create_directories(labels);
      fs::create_directories(dets);
      for (int i = 0; i < kDevkitFrames; ++i) {
        const std::string name = stereodet::FrameId(i) + ".txt";
        LinkOrEmpty(root / "label_2" / name, labels / name);
        LinkOrEmpty(root / "det" / name, dets / name);
      }
    }
    std::cout << out << ": " << frames.size() << " frames, " << num_labels << " labels, "
              << num_dets << " detections\n";
  } catch (const std::exception& e) {
    std::cerr << "write_eval_set: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
