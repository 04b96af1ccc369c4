#include "stereodet/eval/evaluator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;
using testing_objects::Car;
using testing_objects::Car2D;
using testing_objects::CarModerate2D;

std::vector<EvalFrame> ReadFixture(const fs::path& dir) {
  std::vector<EvalFrame> frames;
  std::vector<fs::path> labels;
  for (const auto& e : fs::directory_iterator(dir / "label_2")) labels.push_back(e.path());
  std::sort(labels.begin(), labels.end());
  for (const fs::path& p : labels) {
    EvalFrame f;
    f.id = p.stem().string();
    f.labels = ReadObjects(p, {ObjectFileKind::kLabel, false}).objects;
    f.detections =
        ReadObjects(dir / "det" / p.filename(), {ObjectFileKind::kDetection, false}).objects;
    frames.push_back(std::move(f));
  }
  return frames;
}

// The AP / AOS of KITTI's official devkit on tests/data/eval_small, summed from the arrays it wrote
// (see that folder's README.md).
TEST(EvaluatorTest, AgreesWithTheDevkitOnTheFixture) {
  const fs::path dir = ::stereodet::TestSourceDir() / "tests/data/eval_small";
  const std::vector<EvalFrame> frames = ReadFixture(dir);
  ASSERT_EQ(frames.size(), 12u);
  EvalOptions options;
  options.num_threads = 2;
  const EvalResult result = Evaluate(frames, options);
  std::ifstream expected(dir / "devkit_expected.txt");
  std::string line;
  int checked = 0;
  while (std::getline(expected, line)) {
    std::istringstream in(line);
    std::string name, which;
    double v[3];
    in >> name >> which >> v[0] >> v[1] >> v[2];
    const bool aos = name.find("orientation") != std::string::npos;
    const OverlapKind kind = name.find("_ground") != std::string::npos ? OverlapKind::kBev
                             : name.find("_3d") != std::string::npos   ? OverlapKind::k3D
                                                                       : OverlapKind::k2D;
    const std::string cls = name.substr(0, name.find('_'));
    for (int d = 0; d < 3; ++d) {
      const ClassResult* r = result.Find(cls, kind, static_cast<Difficulty>(d));
      ASSERT_NE(r, nullptr) << line;
      const double ours =
          which == "AP:" ? (aos ? r->aos_r11 : r->ap_r11) : (aos ? r->aos_r40 : r->ap_r40);
      EXPECT_NEAR(ours, v[d], 1e-4) << line << " difficulty " << d;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 72);
}

// The 41-slot precision and orientation arrays the official devkit wrote on tests/data/eval_small
// (its stats_*.txt files, %f, one line per difficulty), slot by slot.
TEST(EvaluatorTest, AgreesWithTheOfficialDevkitsArraysOnTheFixture) {
  const fs::path dir = ::stereodet::TestSourceDir() / "tests/data/eval_small";
  EvalOptions options;
  options.num_threads = 2;
  const EvalResult result = Evaluate(ReadFixture(dir), options);
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir / "devkit")) {
    const std::string stem = e.path().stem().string();  // stats_car_detection_ground
    const std::string name = stem.substr(std::string("stats_").size());
    const std::string cls = name.substr(0, name.find('_'));
    const bool aos = name.find("orientation") != std::string::npos;
    const OverlapKind kind = name.find("_ground") != std::string::npos ? OverlapKind::kBev
                             : name.find("_3d") != std::string::npos   ? OverlapKind::k3D
                                                                       : OverlapKind::k2D;
    std::ifstream in(e.path());
    for (int d = 0; d < 3; ++d) {
      const ClassResult* r = result.Find(cls, kind, static_cast<Difficulty>(d));
      ASSERT_NE(r, nullptr) << stem;
      const std::vector<double>& ours = aos ? r->kitti_aos : r->kitti_precision;
      ASSERT_EQ(ours.size(), 41u) << stem;
      for (int i = 0; i < 41; ++i) {
        double v = 0;
        ASSERT_TRUE(in >> v) << stem;
        EXPECT_NEAR(ours[i], v, 5e-7) << stem << " difficulty " << d << " slot " << i;
      }
    }
    ++files;
  }
  EXPECT_EQ(files, 12);
}

// One-frame data sets on which KITTI's official devkit (devkit_object's evaluate_object.cpp, built
// unmodified against boost 1.74; the prclibo/kitti_eval fork gives the same numbers here) was run;
// the expected numbers are its AP_R40 / AP_R11 (%, from its 41-slot precision output), the same at
// all three difficulties. A-C: overlaps mathematically at tau, decided by the devkit's rounding; F,
// H: two detections at mathematically equal overlaps of one car, which the devkit orders otherwise
// than exact arithmetic; G: a detection 6 cm wider than its car, same centre, length and rotation,
// whose intersection boost 1.74 loses (overlap 0); E / E2: a detection without 3D, with and without
// a DontCare row (both 3D-less squares at (-1000, -1000): suppressed in BEV only).
struct DevkitCase {
  const char* name;
  const char* labels;
  const char* detections;
  const char* class_name;
  double ap[3][2];  // [2D, BEV, 3D][AP_R40, AP_R11]
};

TEST(EvaluatorTest, AgreesWithTheDevkitOnOverlapTiesAndItsGeometryQuirks) {
  const DevkitCase cases[] = {
      {"A: car, same footprint 0.3 m lower: 3D IoU 0.7 exactly, > 0.7 for the devkit",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
       "Car 0.00 0 0.00 100.00 100.00 150.00 200.00 1.70 1.60 3.90 -4.10 1.65 22.70 0.00\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 0.00 100.00 100.00 150.00 200.00 1.70 1.60 3.90 -4.10 1.95 22.70 0.00 0.80\n",
       "Car",
       {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"B: pedestrian, same footprint 0.5 m lower: 3D IoU 0.5 exactly, not > 0.5 for the devkit",
       "Pedestrian 0.00 0 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30\n"
       "Pedestrian 0.00 0 0.00 100.00 100.00 150.00 200.00 1.50 0.60 0.80 2.30 1.80 15.40 1.00\n",
       "Pedestrian -1 -1 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30 "
       "0.90\n"
       "Pedestrian -1 -1 0.00 100.00 100.00 150.00 200.00 1.50 0.60 0.80 2.30 2.30 15.40 1.00 "
       "0.80\n",
       "Pedestrian",
       {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {0.0, 100.0 / 11}}},
      {"C: pedestrian shifted by a third of its length: BEV and 3D IoU 0.5 exactly",
       "Pedestrian 0.00 0 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30\n"
       "Pedestrian 0.00 0 0.00 100.00 100.00 150.00 200.00 1.50 0.60 3.00 2.30 1.80 15.40 0.00\n",
       "Pedestrian -1 -1 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30 "
       "0.90\n"
       "Pedestrian -1 -1 0.00 100.00 100.00 150.00 200.00 1.50 0.60 3.00 3.30 1.80 15.40 0.00 "
       "0.80\n",
       "Pedestrian",
       {{2.5, 100.0 / 11}, {0.0, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"F: detections 0.33 m either side of a car, same rotation",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -0.51 1.65 15.80 0.00\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -0.84 1.65 16.00 0.00\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -0.18 1.65 15.80 0.00 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -0.84 1.65 15.80 0.00 0.80\n",
       "Car",
       {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"H: detections 0.33 m either side of a car, turned +-0.02 rad",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -7.32 1.65 10.46 0.00\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -7.65 1.65 10.66 0.00\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -6.99 1.65 10.46 0.02 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -7.65 1.65 10.46 -0.02 0.80\n",
       "Car",
       {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"G: a detection 6 cm wider than its car, nested between common end lines",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.27 2.41 0.75 9.69 1.74 15.90 -1.57\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -4.00 1.65 30.00 0.30\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.27 2.47 0.75 9.69 1.74 15.90 -1.57 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -4.00 1.65 30.00 0.30 0.80\n",
       "Car",
       {{2.5, 100.0 / 11}, {0.0, 50.0 / 11}, {0.0, 50.0 / 11}}},
      {"E: a detection without 3D inside KITTI's DontCare row: suppressed in BEV, not in 3D",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
       "DontCare -1 -1 -10 600.00 100.00 700.00 150.00 -1 -1 -1 -1000 -1000 -1000 -10\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 -10 100.00 100.00 150.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.95\n",
       "Car",
       {{0.0, 50.0 / 11}, {0.0, 100.0 / 11}, {0.0, 50.0 / 11}}},
      {"E2: the same without the DontCare row",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 -10 100.00 100.00 150.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.95\n",
       "Car",
       {{0.0, 50.0 / 11}, {0.0, 50.0 / 11}, {0.0, 50.0 / 11}}},
  };
  for (const DevkitCase& c : cases) {
    SCOPED_TRACE(c.name);
    EvalFrame frame;
    frame.id = "000000";
    frame.labels = ParseObjects(c.labels, "label", {ObjectFileKind::kLabel}).objects;
    frame.detections = ParseObjects(c.detections, "det", {ObjectFileKind::kDetection}).objects;
    EvalOptions options;
    options.num_threads = 1;
    const EvalResult result = Evaluate({frame}, options);
    for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
      for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
        const ClassResult* r = result.Find(c.class_name, kind, d);
        ASSERT_NE(r, nullptr);
        ASSERT_TRUE(r->evaluated);
        const int k = static_cast<int>(kind);
        EXPECT_NEAR(r->ap_r40, c.ap[k][0], 1e-4)
            << OverlapKindName(kind) << " " << DifficultyName(d);
        EXPECT_NEAR(r->ap_r11, c.ap[k][1], 1e-4)
            << OverlapKindName(kind) << " " << DifficultyName(d);
      }
    }
  }
}

// Labels exactly 40.00 and 25.00 px tall, as KITTI's two-decimal files give them: the official
// devkit ignores a label when height <= the minimum (40 / 25 / 25 px). Three cars, each detected
// exactly (overlap 1 in 2D, BEV and 3D): 100 px (score 0.9), 40.00 px (0.8), 25.00 px (0.7).
//  - Easy: only the 100 px car counts (n = 1); the 40.00 px car is ignored, its detection (40 px,
//  not
//    lower than 40) is assigned to it and is no FP; the 25 px detection is an ignored detection.
//    One TP score -> one threshold -> precision slot 0 = 1: AP_R40 = 0, AP_R11 = 100/11.
//  - Moderate / Hard: the 100 and 40.00 px cars count (n = 2); the 25.00 px one is ignored and its
//    detection (25 px, not lower than 25) is assigned to it. Two thresholds: slots 0, 1 = 1:
//    AP_R40 = 2.5, AP_R11 = 100/11.
// The official devkit's arrays give these (run on this frame). The prclibo fork (height < min)
// counts 2 / 3 / 3 labels and gives AP_R40 2.5 / 5.0 / 5.0.
TEST(EvaluatorTest, LabelsExactly40And25PxTallAreIgnoredLikeTheOfficialDevkit) {
  EvalFrame frame;
  frame.id = "000000";
  frame.labels =
      ParseObjects(
          "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 3.00 1.65 30.00 0.00\n"
          "Car 0.00 0 0.00 612.37 150.37 700.12 190.37 1.50 1.60 3.90 -4.00 1.65 40.00 0.00\n"
          "Car 0.00 0 0.00 800.00 180.12 840.00 205.12 1.50 1.60 3.90 8.00 1.65 50.00 0.00\n",
          "label", {ObjectFileKind::kLabel})
          .objects;
  frame.detections =
      ParseObjects(
          "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
          "Car -1 -1 0.00 612.37 150.37 700.12 190.37 1.50 1.60 3.90 -4.00 1.65 40.00 0.00 0.80\n"
          "Car -1 -1 0.00 800.00 180.12 840.00 205.12 1.50 1.60 3.90 8.00 1.65 50.00 0.00 0.70\n",
          "det", {ObjectFileKind::kDetection})
          .objects;
  ASSERT_EQ(frame.labels[1].box.Height(), 40.0);
  ASSERT_EQ(frame.labels[2].box.Height(), 25.0);
  EvalOptions options;
  options.num_threads = 1;
  options.classes = {KittiClassSpec("Car")};
  const int64_t expected_labels[3] = {1, 2, 2};
  const double expected_r40[3] = {0.0, 2.5, 2.5};
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal}) {
    options.matcher = matcher;
    const EvalResult result = Evaluate({frame}, options);
    for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
      for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
        SCOPED_TRACE(std::string(MatcherName(matcher)) + " " + OverlapKindName(kind) + " " +
                     DifficultyName(d));
        const ClassResult* r = result.Find("Car", kind, d);
        ASSERT_NE(r, nullptr);
        const int k = static_cast<int>(d);
        EXPECT_EQ(r->num_valid_labels, expected_labels[k]);
        // Every label that counts is found, no FP: recall 1 at precision 1.
        EXPECT_EQ(r->curve.back().tp, expected_labels[k]);
        EXPECT_EQ(r->curve.back().fp, 0);
        if (matcher == Matcher::kKitti) {
          EXPECT_NEAR(r->ap_r40, expected_r40[k], 1e-9);
          EXPECT_NEAR(r->ap_r11, 100.0 / 11, 1e-9);
        }
      }
    }
  }
}

// The official devkit evaluates a class in BEV only if some detection of it has x, z != -1000 and
// w, l > 0, and in 3D only if x, y, z != -1000 and h, w, l > 0 (the prclibo/kitti_eval fork tests
// only x != -1000, resp. y != -1000, and would evaluate Car in 3D here). Checked with the official
// devkit on this frame: it writes no stats_car_detection_3d.txt and no
// stats_pedestrian_detection_3d.txt.
TEST(EvaluatorTest, ClassIsEvaluatedInBevAnd3DOnlyWithAValidBoxLikeTheOfficialDevkit) {
  EvalFrame frame;
  frame.id = "000000";
  frame.labels =
      ParseObjects(
          "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 3.00 1.65 30.00 0.00\n"
          "Pedestrian 0.00 0 0.00 500.00 100.00 540.00 200.00 1.70 0.60 0.80 -2.00 1.65 20.00 "
          "0.00\n",
          "label", {ObjectFileKind::kLabel})
          .objects;
  frame.detections =
      ParseObjects(
          "Car -1 -1 0.00 300.00 100.00 400.00 200.00 -1 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
          "Pedestrian -1 -1 0.00 500.00 100.00 540.00 200.00 1.70 0.60 0.80 -2.00 -1000 20.00 0.00 "
          "0.80\n",
          "det", {ObjectFileKind::kDetection})
          .objects;
  EvalOptions options;
  options.num_threads = 1;
  const EvalResult r = Evaluate({frame}, options);
  for (const char* cls : {"Car", "Pedestrian"}) {
    SCOPED_TRACE(cls);
    EXPECT_TRUE(r.Find(cls, OverlapKind::k2D, Difficulty::kEasy)->evaluated);
    EXPECT_TRUE(r.Find(cls, OverlapKind::kBev, Difficulty::kEasy)->evaluated);
    EXPECT_FALSE(r.Find(cls, OverlapKind::k3D, Difficulty::kEasy)->evaluated);
  }
  frame.detections[0].box3d.w = 0;  // no BEV footprint either
  const EvalResult r2 = Evaluate({frame}, options);
  EXPECT_FALSE(r2.Find("Car", OverlapKind::kBev, Difficulty::kEasy)->evaluated);
  EXPECT_TRUE(r2.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
}

// Ground truth evaluated against itself (every label but DontCare as a detection of score 1) on a
// KITTI-val-sized set gives 100 in 2D, BEV and 3D, R40 and R11, in both matchers. (OpenPCDet's
// kitti_object_eval_python is known to give 50 for BEV / 3D there.)
TEST(EvaluatorTest, GroundTruthAgainstItselfScores100) {
  RandomFramesOptions ro;
  ro.num_frames = 3769;
  ro.seed = 7;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  for (EvalFrame& f : frames) {
    f.detections.clear();
    for (const Object& l : f.labels) {
      if (l.IsDontCare()) continue;
      Object d = l;
      d.score = 1.0;
      f.detections.push_back(d);
    }
  }
  EvalOptions options;
  options.num_threads = 2;
  options.metrics = {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D, OverlapKind::kLetBev,
                     OverlapKind::kLet3D};
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal}) {
    options.matcher = matcher;
    const EvalResult result = Evaluate(frames, options);
    ASSERT_EQ(result.results.size(), 45u);
    for (const ClassResult& r : result.results) {
      SCOPED_TRACE(std::string(MatcherName(matcher)) + " " + r.class_name + " " +
                   OverlapKindName(r.metric) + " " + DifficultyName(r.difficulty));
      ASSERT_TRUE(r.evaluated);
      EXPECT_GT(r.num_valid_labels, 40);
      EXPECT_EQ(r.ap_r40, 100.0);
      EXPECT_EQ(r.ap_r11, 100.0);
      // Every detection on its label: affinity exactly 1, so LET-APL is AP.
      EXPECT_EQ(r.has_apl, IsLetKind(r.metric));
      if (IsLetKind(r.metric)) {
        EXPECT_EQ(r.apl_r40, 100.0);
        EXPECT_EQ(r.apl_r11, 100.0);
        EXPECT_FALSE(r.has_aos);
        EXPECT_TRUE(std::isnan(r.aos_r40));
      } else {
        EXPECT_TRUE(std::isnan(r.apl_r40));
      }
    }
  }
}

// LET-3D-AP by hand (docs/metrics.md, "LET-3D-AP"): the sensor at the boxes' centre height, so
// every line of sight is level. Car A 20 m ahead, its detection (score 0.9) 1 m beyond it:
// tolerance 2 m, affinity 0.5, LET-IoU 1, plain 3D IoU 2.9 / 4.9 < 0.7. Car B at (10, 20), its
// detection (0.8) exactly on it: affinity 1. Car C at (-10, 20), its detection (0.7) 3 m beyond
// it along the line of sight: beyond its tolerance of 2.24 m, so no match under LET either.
// Exact matchers, LET-3D: points (R 1/3, P 1, weighted 0.5), (2/3, 1, 0.75), (2/3, 2/3, 0.5):
// AP_R40 = 26 / 40 (recall slots up to 2/3) = 65, APL_R40 = 26 x 0.75 / 40 = 48.75; plain 3D:
// only B, AP_R40 = 13 / 40 x 0.5 = 16.25 (recall 1/3, precision 1/2). KITTI matcher: two TP
// scores, two devkit thresholds, so R40 reads slot 1 only: AP 2.5, APL 0.75 x 2.5.
TEST(EvaluatorTest, LetForgivesErrorAlongTheLineOfSightByHandEveryMatcher) {
  const auto car = [](double x, double z, std::optional<double> score) {
    Object o = Car({100, 100, 200, 200}, score);
    o.box3d.h = 1.5;
    o.box3d.w = 1.6;
    o.box3d.l = 3.9;
    o.box3d.location = Eigen::Vector3d(x, 1.6, z);
    o.alpha = 0;
    return o;
  };
  const double c = 3.0 / std::hypot(10.0, 20.0);  // 3 m along C's line of sight, per metre
  EvalFrame f;
  f.labels = {car(0, 20, std::nullopt), car(10, 20, std::nullopt), car(-10, 20, std::nullopt)};
  f.detections = {car(0, 21, 0.9), car(10, 20, 0.8), car(-10 - 10 * c, 20 + 20 * c, 0.7)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.difficulties = {Difficulty::kEasy};
  options.metrics = {OverlapKind::k3D, OverlapKind::kLet3D, OverlapKind::kLetBev};
  options.let.sensor_m = Eigen::Vector3d(0, 1.6 - 0.75, 0);
  for (const Matcher m : {Matcher::kOptimal, Matcher::kVoc, Matcher::kKitti}) {
    SCOPED_TRACE(MatcherName(m));
    options.matcher = m;
    const EvalResult result = Evaluate({f}, options);
    const ClassResult& plain = *result.Find("Car", OverlapKind::k3D, Difficulty::kEasy);
    for (const OverlapKind kind : {OverlapKind::kLet3D, OverlapKind::kLetBev}) {
      const ClassResult& let = *result.Find("Car", kind, Difficulty::kEasy);
      EXPECT_EQ(let.at_threshold.tp, 2);
      EXPECT_EQ(let.at_threshold.fp, 1);
      EXPECT_EQ(let.at_threshold.fn, 1);
      ASSERT_TRUE(let.has_apl);
      EXPECT_FALSE(let.has_aos);
      if (m == Matcher::kKitti) {
        EXPECT_NEAR(let.ap_r40, 2.5, 1e-9);
        EXPECT_NEAR(let.apl_r40, 0.75 * 2.5, 1e-9);
        ASSERT_EQ(let.kitti_apl.size(), 41u);
        EXPECT_NEAR(let.kitti_apl[0], 0.75, 1e-12);  // the envelope of 0.5 and 0.75
        EXPECT_TRUE(let.kitti_aos.empty());
      } else {
        EXPECT_NEAR(let.ap_r40, 65.0, 1e-9);
        EXPECT_NEAR(let.apl_r40, 48.75, 1e-9);
        ASSERT_EQ(let.curve.size(), 3u);
        EXPECT_NEAR(let.curve[0].similarity, 0.5, 1e-12);
        EXPECT_NEAR(let.curve[1].orientation, 0.75, 1e-12);
      }
    }
    EXPECT_EQ(plain.at_threshold.tp, 1);
    EXPECT_EQ(plain.at_threshold.fp, 2);
    EXPECT_FALSE(plain.has_apl);
    if (m != Matcher::kKitti) {
      EXPECT_NEAR(plain.ap_r40, 16.25, 1e-9);
    }
  }
  // Waymo's tolerance of 0.1 x range is the default; a tighter one (5 %, 0.5 m) rules A out too.
  options.matcher = Matcher::kOptimal;
  options.let.longitudinal_tolerance_fraction = 0.05;
  EXPECT_EQ(
      Evaluate({f}, options).Find("Car", OverlapKind::kLet3D, Difficulty::kEasy)->at_threshold.tp,
      1);
  // --compat openpcdet has no LET.
  options.matcher = Matcher::kKitti;
  options.compat = EvalCompat::kOpenPcdet;
  EXPECT_THROW(Evaluate({f}, options), std::invalid_argument);
}

// LET-APL never exceeds LET-AP (each TP counts at most 1), a LET cell's records report LET-IoU, and
// the LET kinds' counts are those of MatchOverlap's pairs: on random frames, every matcher.
TEST(EvaluatorTest, LetAplIsAtMostApAndOneAndManyThreadsAgree) {
  RandomFramesOptions ro;
  ro.num_frames = 200;
  ro.position_noise = 0.04;
  ro.seed = 37;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.metrics = {OverlapKind::kLetBev, OverlapKind::kLet3D};
  options.keep_records = true;
  for (const Matcher m : {Matcher::kOptimal, Matcher::kVoc, Matcher::kKitti}) {
    SCOPED_TRACE(MatcherName(m));
    options.matcher = m;
    options.num_threads = 1;
    const EvalResult one = Evaluate(frames, options);
    options.num_threads = 2;
    const EvalResult two = Evaluate(frames, options);
    ASSERT_EQ(one.results.size(), two.results.size());
    int with_tp = 0;
    for (size_t k = 0; k < one.results.size(); ++k) {
      const ClassResult& r = one.results[k];
      if (!r.evaluated) continue;
      SCOPED_TRACE(r.class_name + " " + OverlapKindName(r.metric));
      EXPECT_EQ(r.ap_r40, two.results[k].ap_r40);
      EXPECT_EQ(r.apl_r40, two.results[k].apl_r40);
      EXPECT_LE(r.apl_r40, r.ap_r40 + 1e-9);
      EXPECT_LE(r.apl_r11, r.ap_r11 + 1e-9);
      with_tp += r.at_threshold.tp > 0 ? 1 : 0;
      for (const MatchRecord& rec : r.records) {
        if (rec.outcome != Outcome::kTp) continue;
        const EvalFrame& frame = frames[rec.frame];
        EXPECT_EQ(rec.iou, MatchOverlap(r.metric, frame.detections[rec.detection],
                                        frame.labels[rec.label], options.let));
        EXPECT_GE(rec.iou, r.min_overlap);
      }
    }
    EXPECT_GT(with_tp, 6);
  }
}

TEST(EvaluatorTest, ClassWithoutDetectionsIsNotEvaluatedLikeTheDevkit) {
  RandomFramesOptions ro;
  ro.num_frames = 20;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  for (EvalFrame& f : frames) {
    std::erase_if(f.detections, [](const Object& d) { return d.type == "Cyclist"; });
  }
  EvalOptions options;
  const EvalResult r = Evaluate(frames, options);
  EXPECT_FALSE(r.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  EXPECT_TRUE(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  options.require_detections = false;
  const EvalResult all = Evaluate(frames, options);
  EXPECT_TRUE(all.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  EXPECT_EQ(all.Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->ap_r40, 0.0);
}

TEST(EvaluatorTest, AlphaMinus10AnywhereDisablesAos) {
  RandomFramesOptions ro;
  ro.num_frames = 10;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  EXPECT_TRUE(Evaluate(frames, options).aos_computed);
  frames[3].detections.at(0).alpha = -10;
  const EvalResult r = Evaluate(frames, options);
  EXPECT_FALSE(r.aos_computed);
  EXPECT_TRUE(std::isnan(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->aos_r40));
}

// The three matchers agree on TP counts at each threshold up to greedy's mistakes, and the optimal
// curve's counts at the operating threshold equal its association's.
TEST(EvaluatorTest, OptimalCurveMatchesItsAssociationAndBeatsGreedy) {
  RandomFramesOptions ro;
  ro.num_frames = 60;
  ro.crowded = true;
  ro.labels_per_frame = 9;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  EvalOptions options;
  options.score_threshold = 0.5;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::kBev};
  const EvalResult kitti = Evaluate(frames, options);
  options.matcher = Matcher::kOptimal;
  const EvalResult optimal = Evaluate(frames, options);
  options.matcher = Matcher::kVoc;
  const EvalResult voc = Evaluate(frames, options);
  for (Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
    const ClassResult& o = *optimal.Find("Car", OverlapKind::kBev, d);
    CurvePoint at;
    for (const CurvePoint& p : o.curve) {
      if (p.threshold >= 0.5) at = p;
    }
    EXPECT_EQ(at.tp, o.at_threshold.tp);
    EXPECT_EQ(at.fp, o.at_threshold.fp);
    EXPECT_EQ(at.fn, o.at_threshold.fn);
    EXPECT_GE(o.at_threshold.tp, kitti.Find("Car", OverlapKind::kBev, d)->at_threshold.tp);
    EXPECT_GE(o.at_threshold.tp, voc.Find("Car", OverlapKind::kBev, d)->at_threshold.tp);
    EXPECT_GT(o.ap_r40, 0.0);
    EXPECT_FALSE(std::isnan(o.ap_voc));
  }
}

// 26 perfect detections of 27 labels: the devkit's AP_R40 is capped at (TP - 1) / 40 = 62.5 with 40
// or fewer labels (every TP score is a threshold, 26 of its 41 slots are filled, slot 0 is not
// summed); the exact curve of the optimal matcher gives 95 (38 of 40 recall positions reached).
TEST(EvaluatorTest, SmallSampleKittiApR40IsCappedAtFortyLabelsOrFewer) {
  EvalFrame f;
  for (int i = 0; i < 27; ++i) {
    const Box2D box{i * 45.0, 0, i * 45.0 + 40, 50};
    f.labels.push_back(Car(box));
    if (i < 26) f.detections.push_back(Car(box, 0.5 + i * 0.01));
  }
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  const EvalResult kitti = Evaluate({f}, options);
  const ClassResult& k = kitti.results.at(0);
  EXPECT_EQ(k.num_valid_labels, 27);
  EXPECT_TRUE(IsSmallSample(k));
  EXPECT_NEAR(k.ap_r40, 62.5, 1e-9);
  options.matcher = Matcher::kOptimal;
  const ClassResult o = Evaluate({f}, options).results.at(0);
  EXPECT_NEAR(o.ap_r40, 95.0, 1e-9);
  // 41 labels are not a small sample.
  for (int i = 27; i < 41; ++i) f.labels.push_back(Car({i * 45.0, 0, i * 45.0 + 40, 50}));
  options.matcher = Matcher::kKitti;
  EXPECT_FALSE(IsSmallSample(Evaluate({f}, options).results.at(0)));
}

// AOS by hand for the exact matchers: two labels (alpha 0), found at scores 0.9 (alpha 0,
// similarity 1) and 0.8 (alpha pi/2, similarity 1/2). Orientation ratio 1 at recall 1/2, 3/4 at
// recall 1: AOS_R40 = (20 * 1 + 20 * 0.75) / 40 = 87.5 %, AOS_R11 = (6 + 5 * 0.75) / 11.
TEST(EvaluatorTest, AosOfExactMatchersByHand) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 100, 100, 0), Car2D(300, 0, 400, 100, 0)};
  f.detections = {Car2D(0, 0, 100, 100, 0, 0.9), Car2D(300, 0, 400, 100, M_PI / 2, 0.8)};
  for (Matcher m : {Matcher::kOptimal, Matcher::kVoc}) {
    const EvalResult result = Evaluate({f}, CarModerate2D(m));
    const ClassResult& r = result.results.at(0);
    ASSERT_TRUE(r.has_aos) << MatcherName(m);
    ASSERT_EQ(r.curve.size(), 2u);
    EXPECT_NEAR(r.curve[0].orientation, 1.0, 1e-12);
    EXPECT_NEAR(r.curve[1].similarity, 1.5, 1e-12);
    EXPECT_NEAR(r.aos_r40, 87.5, 1e-9) << MatcherName(m);
    EXPECT_NEAR(r.aos_r11, (6 + 5 * 0.75) / 11 * 100, 1e-9) << MatcherName(m);
    EXPECT_NEAR(r.ap_r40, 100.0, 1e-9);
  }
}

// With every orientation right, AOS equals AP; and the optimal curve's similarity at each point
// equals that of the association at that threshold, summed over frames.
TEST(EvaluatorTest, AosPerfectOrientationGivesApAndCurveAgreesWithAssociations) {
  RandomFramesOptions ro;
  ro.num_frames = 40;
  ro.crowded = true;
  std::vector<EvalFrame> frames = RandomFrames(ro);
  for (Matcher m : {Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options;
    options.metrics = {OverlapKind::k2D};
    options.matcher = m;
    const EvalResult result = Evaluate(frames, options);
    ASSERT_TRUE(result.aos_computed);
    for (const ClassResult& r : result.results) {
      if (!r.evaluated) continue;
      ASSERT_TRUE(r.has_aos);
      EXPECT_LE(r.aos_r40, r.ap_r40 + 1e-9);
      const ClassSpec spec = KittiClassSpec(r.class_name);
      for (size_t k = 0; k < r.curve.size(); k += 3) {
        double similarity = 0.0;
        for (const EvalFrame& frame : frames) {
          const ClassFrame cf = PrepareClassFrame(frame, spec, OverlapKind::k2D);
          const FrameAssociation a = Associate(m, cf, r.difficulty, r.curve[k].threshold);
          for (int i = 0; i < cf.num_labels(); ++i) {
            if (a.label_outcome[i] != Outcome::kTp) continue;
            similarity += (1 + std::cos(cf.det_alpha[a.label_det[i]] - cf.label_alpha[i])) / 2;
          }
        }
        EXPECT_NEAR(r.curve[k].similarity, similarity, 1e-9) << MatcherName(m) << ' ' << k;
      }
    }
  }
  for (EvalFrame& frame : frames) {
    for (Object& d : frame.detections) d.alpha = 0;
    for (Object& l : frame.labels) l.alpha = 0;
  }
  for (Matcher m : {Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options;
    options.metrics = {OverlapKind::k2D};
    options.matcher = m;
    const EvalResult result = Evaluate(frames, options);
    for (const ClassResult& r : result.results) {
      if (!r.evaluated) continue;
      EXPECT_NEAR(r.aos_r40, r.ap_r40, 1e-9) << r.class_name;
      EXPECT_NEAR(r.aos_r11, r.ap_r11, 1e-9) << r.class_name;
    }
  }
}

// Both NaN, or equal: "identical" for results where NaN marks "not computed".
bool Same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

void ExpectSameCurve(const std::vector<CurvePoint>& a, const std::vector<CurvePoint>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_TRUE(Same(a[k].threshold, b[k].threshold)) << k;
    EXPECT_EQ(a[k].tp, b[k].tp) << k;
    EXPECT_EQ(a[k].fp, b[k].fp) << k;
    EXPECT_EQ(a[k].fn, b[k].fn) << k;
    EXPECT_TRUE(Same(a[k].precision, b[k].precision)) << k;
    EXPECT_TRUE(Same(a[k].recall, b[k].recall)) << k;
    EXPECT_TRUE(Same(a[k].similarity, b[k].similarity)) << k;
  }
}

void ExpectSamePoint(const OperatingPoint& a, const OperatingPoint& b) {
  EXPECT_TRUE(Same(a.threshold, b.threshold));
  EXPECT_EQ(a.tp, b.tp);
  EXPECT_EQ(a.fp, b.fp);
  EXPECT_EQ(a.fn, b.fn);
  EXPECT_TRUE(Same(a.f1, b.f1));
}

void ExpectSameFilteredCurve(const FilteredCurve& a, const FilteredCurve& b) {
  ExpectSameCurve(a.curve, b.curve);
  for (auto [x, y] : {std::pair{a.ap_r40, b.ap_r40},
                      {a.ap_r11, b.ap_r11},
                      {a.ap_voc, b.ap_voc},
                      {a.aos_r40, b.aos_r40},
                      {a.aos_r11, b.aos_r11}}) {
    EXPECT_TRUE(Same(x, y)) << x << " vs " << y;
  }
}

// Everything a ClassResult holds, exactly (no tolerance: the number of threads must not change a
// bit of the evaluation).
void ExpectSameClassResult(const ClassResult& a, const ClassResult& b) {
  SCOPED_TRACE(a.class_name + " " + OverlapKindName(a.metric) + " " + DifficultyName(a.difficulty));
  ASSERT_EQ(a.class_name, b.class_name);
  ASSERT_EQ(a.metric, b.metric);
  ASSERT_EQ(a.difficulty, b.difficulty);
  ASSERT_EQ(a.evaluated, b.evaluated);
  EXPECT_EQ(a.num_valid_labels, b.num_valid_labels);
  EXPECT_EQ(a.num_detections, b.num_detections);
  for (auto [x, y] : {std::pair{a.ap_r40, b.ap_r40},
                      {a.ap_r11, b.ap_r11},
                      {a.ap_voc, b.ap_voc},
                      {a.aos_r40, b.aos_r40},
                      {a.aos_r11, b.aos_r11}}) {
    EXPECT_TRUE(Same(x, y)) << x << " vs " << y;
  }
  ExpectSameCurve(a.curve, b.curve);
  EXPECT_EQ(a.kitti_precision.size(), b.kitti_precision.size());
  for (size_t k = 0; k < std::min(a.kitti_precision.size(), b.kitti_precision.size()); ++k) {
    EXPECT_TRUE(Same(a.kitti_precision[k], b.kitti_precision[k])) << k;
  }
  EXPECT_EQ(a.kitti_thresholds, b.kitti_thresholds);
  ExpectSamePoint(a.at_threshold, b.at_threshold);
  ExpectSamePoint(a.best_f1, b.best_f1);
  ASSERT_EQ(a.filtered.has_value(), b.filtered.has_value());
  if (a.filtered) {
    ExpectSamePoint(a.filtered->naive, b.filtered->naive);
    ExpectSamePoint(a.filtered->stable, b.filtered->stable);
    ExpectSameFilteredCurve(a.filtered->naive_curve, b.filtered->naive_curve);
    ExpectSameFilteredCurve(a.filtered->stable_curve, b.filtered->stable_curve);
  }
  EXPECT_TRUE(Same(a.brier.over_labels, b.brier.over_labels));
  EXPECT_TRUE(Same(a.brier.over_detections, b.brier.over_detections));
  EXPECT_TRUE(Same(a.brier.over_all, b.brier.over_all));
  EXPECT_EQ(a.brier.num_all_terms, b.brier.num_all_terms);
  EXPECT_TRUE(Same(a.calibration.ece, b.calibration.ece));
  EXPECT_EQ(a.calibration.num_detections, b.calibration.num_detections);
  ASSERT_EQ(a.localization.size(), b.localization.size());
  for (size_t k = 0; k < a.localization.size(); ++k) {
    EXPECT_EQ(a.localization[k].count, b.localization[k].count);
    EXPECT_TRUE(Same(a.localization[k].centre_error_mean_m, b.localization[k].centre_error_mean_m));
    EXPECT_TRUE(Same(a.localization[k].depth_error_mean_m, b.localization[k].depth_error_mean_m));
  }
  ASSERT_EQ(a.records.size(), b.records.size());
  for (size_t k = 0; k < a.records.size(); ++k) {
    EXPECT_EQ(a.records[k].frame, b.records[k].frame) << k;
    EXPECT_EQ(a.records[k].detection, b.records[k].detection) << k;
    EXPECT_EQ(a.records[k].label, b.records[k].label) << k;
    EXPECT_EQ(a.records[k].outcome, b.records[k].outcome) << k;
    EXPECT_EQ(a.records[k].label_valid, b.records[k].label_valid) << k;
    EXPECT_TRUE(Same(a.records[k].iou, b.records[k].iou)) << k;
  }
}

// Property: the evaluation does not depend on the number of threads (CONTRIBUTING.md), for every
// matcher, with every part switched on (filters in both modes, records, 3D), on random frames.
TEST(EvaluatorTest, OneAndManyThreadsGiveIdenticalEvaluations) {
  for (const uint64_t seed : {3u, 4u}) {
    RandomFramesOptions ro;
    ro.num_frames = 24;
    ro.crowded = seed == 3;
    ro.score_decimals = seed == 4 ? 2 : 0;  // ties in score, as KITTI files have
    ro.seed = seed;
    const std::vector<EvalFrame> frames = RandomFrames(ro);
    for (const Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
      SCOPED_TRACE(std::string(MatcherName(m)) + " seed " + std::to_string(seed));
      EvalOptions options;
      options.matcher = m;
      options.filter.conditions = ParseFilterConditions("min-area=2000,max-distance=35");
      options.score_threshold = 0.4;
      options.keep_records = true;
      options.num_threads = 1;
      const EvalResult one = Evaluate(frames, options);
      int evaluated = 0;
      for (const int threads : {2, 5}) {
        options.num_threads = threads;
        const EvalResult many = Evaluate(frames, options);
        EXPECT_EQ(many.aos_computed, one.aos_computed);
        EXPECT_EQ(many.scores.num_scores, one.scores.num_scores);
        ASSERT_EQ(many.results.size(), one.results.size());
        for (size_t i = 0; i < one.results.size(); ++i) {
          ExpectSameClassResult(one.results[i], many.results[i]);
          evaluated += one.results[i].evaluated && !one.results[i].records.empty() ? 1 : 0;
        }
      }
      EXPECT_GT(evaluated, 0);  // the comparison compared something
    }
  }
}

}  // namespace
}  // namespace stereodet
