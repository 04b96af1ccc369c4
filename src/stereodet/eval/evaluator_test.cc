#include "stereodet/eval/evaluator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/kitti/label_io.h"

namespace stereodet {
namespace {

namespace fs = std::filesystem;

std::vector<EvalFrame> ReadFixture(const fs::path& dir) {
  std::vector<EvalFrame> frames;
  std::vector<fs::path> labels;
  for (const auto& e : fs::directory_iterator(dir / "label_2")) labels.push_back(e.path());
  std::sort(labels.begin(), labels.end());
  for (const fs::path& p : labels) {
    EvalFrame f;
    f.id = p.stem().string();
    f.labels = ReadObjects(p, {ObjectFileKind::kLabel, false}).objects;
    f.detections = ReadObjects(dir / "det" / p.filename(), {ObjectFileKind::kDetection, false}).objects;
    frames.push_back(std::move(f));
  }
  return frames;
}

// The AP / AOS of KITTI's official devkit on tests/data/eval_small, summed from the arrays it wrote
// (see that folder's README.md).
TEST(Evaluator, AgreesWithTheDevkitOnTheFixture) {
  const fs::path dir = fs::path(STEREODET_SOURCE_DIR) / "tests/data/eval_small";
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
      const double ours = which == "AP:" ? (aos ? r->aos_r11 : r->ap_r11) : (aos ? r->aos_r40 : r->ap_r40);
      EXPECT_NEAR(ours, v[d], 1e-4) << line << " difficulty " << d;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 72);
}

// The 41-slot precision and orientation arrays the official devkit wrote on tests/data/eval_small
// (its stats_*.txt files, %f, one line per difficulty), slot by slot.
TEST(Evaluator, AgreesWithTheOfficialDevkitsArraysOnTheFixture) {
  const fs::path dir = fs::path(STEREODET_SOURCE_DIR) / "tests/data/eval_small";
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

TEST(Evaluator, AgreesWithTheDevkitOnOverlapTiesAndItsGeometryQuirks) {
  const DevkitCase cases[] = {
      {"A: car, same footprint 0.3 m lower: 3D IoU 0.7 exactly, > 0.7 for the devkit",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
       "Car 0.00 0 0.00 100.00 100.00 150.00 200.00 1.70 1.60 3.90 -4.10 1.65 22.70 0.00\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 0.00 100.00 100.00 150.00 200.00 1.70 1.60 3.90 -4.10 1.95 22.70 0.00 0.80\n",
       "Car", {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"B: pedestrian, same footprint 0.5 m lower: 3D IoU 0.5 exactly, not > 0.5 for the devkit",
       "Pedestrian 0.00 0 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30\n"
       "Pedestrian 0.00 0 0.00 100.00 100.00 150.00 200.00 1.50 0.60 0.80 2.30 1.80 15.40 1.00\n",
       "Pedestrian -1 -1 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30 0.90\n"
       "Pedestrian -1 -1 0.00 100.00 100.00 150.00 200.00 1.50 0.60 0.80 2.30 2.30 15.40 1.00 0.80\n",
       "Pedestrian", {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {0.0, 100.0 / 11}}},
      {"C: pedestrian shifted by a third of its length: BEV and 3D IoU 0.5 exactly",
       "Pedestrian 0.00 0 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30\n"
       "Pedestrian 0.00 0 0.00 100.00 100.00 150.00 200.00 1.50 0.60 3.00 2.30 1.80 15.40 0.00\n",
       "Pedestrian -1 -1 0.00 300.00 100.00 340.00 200.00 1.50 0.60 0.80 3.00 1.80 30.00 0.30 0.90\n"
       "Pedestrian -1 -1 0.00 100.00 100.00 150.00 200.00 1.50 0.60 3.00 3.30 1.80 15.40 0.00 0.80\n",
       "Pedestrian", {{2.5, 100.0 / 11}, {0.0, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"F: detections 0.33 m either side of a car, same rotation",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -0.51 1.65 15.80 0.00\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -0.84 1.65 16.00 0.00\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -0.18 1.65 15.80 0.00 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -0.84 1.65 15.80 0.00 0.80\n",
       "Car", {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"H: detections 0.33 m either side of a car, turned +-0.02 rad",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -7.32 1.65 10.46 0.00\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -7.65 1.65 10.66 0.00\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 -6.99 1.65 10.46 0.02 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -7.65 1.65 10.46 -0.02 0.80\n",
       "Car", {{2.5, 100.0 / 11}, {2.5, 100.0 / 11}, {2.5, 100.0 / 11}}},
      {"G: a detection 6 cm wider than its car, nested between common end lines",
       "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.27 2.41 0.75 9.69 1.74 15.90 -1.57\n"
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -4.00 1.65 30.00 0.30\n",
       "Car -1 -1 0.00 100.00 100.00 200.00 200.00 1.27 2.47 0.75 9.69 1.74 15.90 -1.57 0.90\n"
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 -4.00 1.65 30.00 0.30 0.80\n",
       "Car", {{2.5, 100.0 / 11}, {0.0, 50.0 / 11}, {0.0, 50.0 / 11}}},
      {"E: a detection without 3D inside KITTI's DontCare row: suppressed in BEV, not in 3D",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
       "DontCare -1 -1 -10 600.00 100.00 700.00 150.00 -1 -1 -1 -1000 -1000 -1000 -10\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 -10 100.00 100.00 150.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.95\n",
       "Car", {{0.0, 50.0 / 11}, {0.0, 100.0 / 11}, {0.0, 50.0 / 11}}},
      {"E2: the same without the DontCare row",
       "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n",
       "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
       "Car -1 -1 -10 100.00 100.00 150.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.95\n",
       "Car", {{0.0, 50.0 / 11}, {0.0, 50.0 / 11}, {0.0, 50.0 / 11}}},
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
        EXPECT_NEAR(r->ap_r40, c.ap[k][0], 1e-4) << OverlapKindName(kind) << " " << DifficultyName(d);
        EXPECT_NEAR(r->ap_r11, c.ap[k][1], 1e-4) << OverlapKindName(kind) << " " << DifficultyName(d);
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
TEST(Evaluator, LabelsExactly40And25PxTallAreIgnoredLikeTheOfficialDevkit) {
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
TEST(Evaluator, ClassIsEvaluatedInBevAnd3DOnlyWithAValidBoxLikeTheOfficialDevkit) {
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
TEST(Evaluator, GroundTruthAgainstItselfScores100) {
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
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal}) {
    options.matcher = matcher;
    const EvalResult result = Evaluate(frames, options);
    ASSERT_EQ(result.results.size(), 27u);
    for (const ClassResult& r : result.results) {
      SCOPED_TRACE(std::string(MatcherName(matcher)) + " " + r.class_name + " " +
                   OverlapKindName(r.metric) + " " + DifficultyName(r.difficulty));
      ASSERT_TRUE(r.evaluated);
      EXPECT_GT(r.num_valid_labels, 40);
      EXPECT_EQ(r.ap_r40, 100.0);
      EXPECT_EQ(r.ap_r11, 100.0);
    }
  }
}

TEST(Evaluator, ClassWithoutDetectionsIsNotEvaluatedLikeTheDevkit) {
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

TEST(Evaluator, AlphaMinus10AnywhereDisablesAos) {
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
TEST(Evaluator, OptimalCurveMatchesItsAssociationAndBeatsGreedy) {
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

TEST(Curves, InterpolatedApOfAPerfectCurveIs100) {
  // 40 labels, found one by one with precision 1: R40 = 100 (no devkit slot quirk here).
  std::vector<CurveEvent> events;
  for (int i = 0; i < 40; ++i) events.push_back(CurveEvent{1.0 - i / 100.0, 1, 0, -1});
  const std::vector<CurvePoint> curve = BuildCurve(events, 40);
  EXPECT_DOUBLE_EQ(InterpolatedApR40(curve), 100.0);
  EXPECT_DOUBLE_EQ(InterpolatedApR11(curve), 100.0);
  EXPECT_DOUBLE_EQ(EveryPointAp(curve), 100.0);
  EXPECT_DOUBLE_EQ(BestF1(curve).f1, 1.0);
}

TEST(Curves, EveryPointApIntegratesTheEnvelope) {
  // Labels: 2. Scores: TP, FP, TP -> (P, R) = (1, .5), (.5, .5), (2/3, 1).
  const std::vector<CurvePoint> curve =
      BuildCurve({{0.9, 1, 0, -1}, {0.8, 0, 1, 0}, {0.7, 1, 0, -1}}, 2);
  ASSERT_EQ(curve.size(), 3u);
  EXPECT_NEAR(EveryPointAp(curve), (0.5 * 1.0 + 0.5 * 2.0 / 3.0) * 100, 1e-12);
  // R11: r = 0..0.5 -> 1 (6 levels), r = 0.6..1 -> 2/3 (5 levels).
  EXPECT_NEAR(InterpolatedApR11(curve), (6 * 1.0 + 5 * 2.0 / 3.0) / 11 * 100, 1e-12);
}

// Brier three ways, by hand: one TP (s = 0.9), one FP (s = 0.4), one FN.
TEST(ScoreMetrics, BrierThreeWaysByHand) {
  EvalFrame f;
  Object l1, l2, d1, d2;
  l1.type = l2.type = d1.type = d2.type = "Car";
  l1.box = {0, 0, 100, 100};
  l2.box = {300, 0, 400, 100};
  d1.box = {0, 0, 100, 100};
  d1.score = 0.9;
  d2.box = {600, 0, 700, 100};
  d2.score = 0.4;
  f.labels = {l1, l2};
  f.detections = {d1, d2};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult result = Evaluate({f}, options);  // keeps the result alive
    const ClassResult& r = result.results.at(0);
    EXPECT_NEAR(r.brier.over_labels, (0.01 + 1.0) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_detections, (0.01 + 0.16) / 2, 1e-12);
    EXPECT_NEAR(r.brier.over_all, (0.01 + 0.16 + 1.0) / 3, 1e-12);
    // Reliability, 10 bins: 0.4 (FP) in bin 4, 0.9 (TP) in bin 9. ECE = (0.4 + 0.1) / 2.
    EXPECT_EQ(r.calibration.bins[4].count, 1);
    EXPECT_EQ(r.calibration.bins[9].tp_fraction, 1.0);
    EXPECT_NEAR(r.calibration.ece, 0.25, 1e-12);
  }
}

Object Car(Box2D box, std::optional<double> score = std::nullopt) {
  Object o;
  o.type = "Car";
  o.box = box;
  o.score = score;
  return o;
}

// Brier over labels has a fixed support: one term per valid label whatever the detector did. Two
// detectors on the same two labels (l1 100 px tall, l2 30 px, both valid at Moderate): A finds l1
// (0.9) and misses l2; B finds l1 (0.9) and covers l2 with a 24 px detection, which Moderate
// ignores (< 25 px), so l2 is excused (neither TP nor FN). Both are scored over 2 label terms:
// ((1 - 0.9)^2 + 1) / 2 = 0.505. (Before, B's l2 dropped out: 1 term, 0.01.)
TEST(ScoreMetrics, BrierOverLabelsHasAFixedSupport) {
  const Object l1 = Car({0, 0, 100, 100}), l2 = Car({300, 0, 400, 30});
  EvalFrame a, b;
  a.labels = b.labels = {l1, l2};
  a.detections = {Car({0, 0, 100, 100}, 0.9), Car({600, 0, 700, 100}, 0.4)};
  b.detections = {Car({0, 0, 100, 100}, 0.9), Car({300, 0, 400, 24}, 0.7)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult ra = Evaluate({a}, options), rb = Evaluate({b}, options);
    const ClassResult &ca = ra.results.at(0), &cb = rb.results.at(0);
    EXPECT_EQ(cb.at_threshold.fn, 0) << MatcherName(m);  // l2 is excused, not missed
    EXPECT_EQ(ca.num_valid_labels, 2);
    EXPECT_EQ(ca.brier.num_label_terms, ca.num_valid_labels) << MatcherName(m);
    EXPECT_EQ(cb.brier.num_label_terms, cb.num_valid_labels) << MatcherName(m);
    EXPECT_NEAR(ca.brier.over_labels, 0.505, 1e-12) << MatcherName(m);
    EXPECT_NEAR(cb.brier.over_labels, 0.505, 1e-12) << MatcherName(m);
    // Over all: the label terms plus one s^2 per FP (A's 0.4; B has none).
    EXPECT_EQ(ca.brier.num_all_terms, 3);
    EXPECT_NEAR(ca.brier.over_all, (0.01 + 1.0 + 0.16) / 3, 1e-12);
    EXPECT_EQ(cb.brier.num_all_terms, 2);
    EXPECT_NEAR(cb.brier.over_all, 0.505, 1e-12);
  }
}

// Brier and ECE need probabilities. Logit scores (2.0 TP, -1.0 FP): left out (NaN) unless
// --score-transform sigmoid; AP, the curve and the operating point are the raw scores' either way.
TEST(ScoreMetrics, ScoresOutsideTheUnitIntervalLeaveBrierOutUnlessTransformed) {
  EvalFrame f;
  f.labels = {Car({0, 0, 100, 100}), Car({300, 0, 400, 100})};
  f.detections = {Car({0, 0, 100, 100}, 2.0), Car({600, 0, 700, 100}, -1.0),
                  Car({300, 0, 400, 100}, 40.0)};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal}) {
    options.matcher = m;
    options.score_transform = ScoreTransform::kNone;
    const EvalResult raw = Evaluate({f}, options);
    EXPECT_FALSE(raw.probability_metrics);
    EXPECT_EQ(raw.scores.num_scores, 3);
    EXPECT_EQ(raw.scores.num_outside_unit, 3);
    EXPECT_EQ(raw.scores.min_score, -1.0);
    EXPECT_EQ(raw.scores.max_score, 40.0);
    options.score_transform = ScoreTransform::kSigmoid;
    const EvalResult sig = Evaluate({f}, options);
    EXPECT_TRUE(sig.probability_metrics);
    ASSERT_EQ(raw.results.size(), sig.results.size());
    for (size_t k = 0; k < raw.results.size(); ++k) {
      const ClassResult &r = raw.results[k], &s = sig.results[k];
      EXPECT_TRUE(std::isnan(r.brier.over_labels));
      EXPECT_TRUE(std::isnan(r.brier.over_detections));
      EXPECT_TRUE(std::isnan(r.brier.over_all));
      EXPECT_TRUE(std::isnan(r.calibration.ece));
      EXPECT_EQ(r.brier.num_label_terms, 2);  // the support is still there
      // AP, the curve and the operating point do not depend on the transform (bit for bit).
      EXPECT_EQ(r.ap_r40, s.ap_r40);
      EXPECT_EQ(r.ap_r11, s.ap_r11);
      ASSERT_EQ(r.curve.size(), s.curve.size());
      for (size_t i = 0; i < r.curve.size(); ++i)
        EXPECT_EQ(r.curve[i].threshold, s.curve[i].threshold);
      EXPECT_EQ(r.at_threshold.tp, s.at_threshold.tp);
      // Sigmoid: the TPs 2.0 and 40.0 (sigmoid(40) = 1 - 4e-18, rounds to 1), the FP -1.0.
      const double p2 = 1.0 / (1.0 + std::exp(-2.0)), pm1 = 1.0 / (1.0 + std::exp(1.0));
      EXPECT_NEAR(s.brier.over_labels, ((1 - p2) * (1 - p2) + 0.0) / 2, 1e-12);
      EXPECT_NEAR(s.brier.over_detections, ((1 - p2) * (1 - p2) + pm1 * pm1) / 3, 1e-12);
      EXPECT_FALSE(std::isnan(s.calibration.ece));
    }
  }
  EXPECT_EQ(ApplyScoreTransform(ScoreTransform::kSigmoid, 0.0), 0.5);
  EXPECT_EQ(ApplyScoreTransform(ScoreTransform::kSigmoid, -1000.0), 0.0);
  EXPECT_EQ(ParseScoreTransform("SIGMOID"), ScoreTransform::kSigmoid);
  EXPECT_FALSE(ParseScoreTransform("softmax").has_value());
}

// 26 perfect detections of 27 labels: the devkit's AP_R40 is capped at (TP - 1) / 40 = 62.5 with 40
// or fewer labels (every TP score is a threshold, 26 of its 41 slots are filled, slot 0 is not
// summed); the exact curve of the optimal matcher gives 95 (38 of 40 recall positions reached).
TEST(SmallSample, KittiApR40IsCappedAtFortyLabelsOrFewer) {
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

// The paper's instability of naive filtering: a label just under a min-area bound whose matched
// detection is just above it. Naive: the label is struck, the detection becomes a FP. Stable: the
// pair is dropped as a whole (neither TP nor FP).
TEST(Filters, NaiveFilterTurnsAMatchedDetectionIntoAFalsePositive) {
  EvalFrame f;
  Object label, det;
  label.type = det.type = "Car";
  label.box = {0, 0, 99, 100};  // area 9900
  det.box = {0, 0, 101, 100};   // area 10100, IoU 0.98
  det.score = 0.9;
  f.labels = {label};
  f.detections = {det};
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  options.filter.conditions = ParseFilterConditions("min-area=10000");
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    options.matcher = m;
    const EvalResult result = Evaluate({f}, options);  // keeps the result alive
    const ClassResult& r = result.results.at(0);
    ASSERT_TRUE(r.filtered.has_value());
    EXPECT_EQ(r.filtered->naive.fp, 1) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.fp, 0) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.tp, 0) << MatcherName(m);
    EXPECT_EQ(r.filtered->stable.fn, 0) << MatcherName(m);
  }
  options.filter.conditions.clear();  // the sweep adds its own bound
  const std::vector<SweepRow> rows =
      FilterSweep({f}, options, FilterBound::kMinArea, 9000, 11000, 1000);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].stats.stable.tp, 1);  // 9000: both pass
  EXPECT_EQ(rows[1].stats.naive.fp, 1);   // 10000: the naive FP
  EXPECT_EQ(rows[2].stats.naive.fp, 0);   // 11000: both struck
}

Object Car2D(double left, double top, double right, double bottom, double alpha, double score = -1) {
  Object o;
  o.type = "Car";
  o.box = {left, top, right, bottom};
  o.alpha = alpha;
  if (score >= 0) o.score = score;  // labels carry no score
  return o;
}

EvalOptions CarModerate2D(Matcher matcher) {
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  options.metrics = {OverlapKind::k2D};
  options.difficulties = {Difficulty::kModerate};
  options.matcher = matcher;
  return options;
}

// AOS by hand for the exact matchers: two labels (alpha 0), found at scores 0.9 (alpha 0,
// similarity 1) and 0.8 (alpha pi/2, similarity 1/2). Orientation ratio 1 at recall 1/2, 3/4 at
// recall 1: AOS_R40 = (20 * 1 + 20 * 0.75) / 40 = 87.5 %, AOS_R11 = (6 + 5 * 0.75) / 11.
TEST(Aos, ExactMatchersByHand) {
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

// The optimal association re-pairs a label when a better detection arrives: label A (alpha 0) is
// first taken by a detection of alpha pi (similarity 0); at a lower score a detection that only
// fits A arrives while the first one also fits label B, so the maximum matching pairs both and the
// similarity of A's pair changes.
TEST(Aos, OptimalSimilarityFollowsTheAssociationAtEachScore) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 100, 100, 0), Car2D(20, 0, 120, 100, 0)};
  f.detections = {Car2D(10, 0, 110, 100, M_PI, 0.9), Car2D(0, 0, 100, 100, 0, 0.8)};
  EvalOptions options = CarModerate2D(Matcher::kOptimal);
  options.classes[0].min_overlap = {0.5, 0.5, 0.5};
  const EvalResult result = Evaluate({f}, options);
  const ClassResult& r = result.results.at(0);
  ASSERT_EQ(r.curve.size(), 2u);
  EXPECT_EQ(r.curve[0].tp, 1);
  EXPECT_NEAR(r.curve[0].similarity, 0.0, 1e-12);
  EXPECT_EQ(r.curve[1].tp, 2);
  EXPECT_NEAR(r.curve[1].similarity, 1.0, 1e-12);  // (0 for B's pair) + 1 for A's
}

// With every orientation right, AOS equals AP; and the optimal curve's similarity at each point
// equals that of the association at that threshold, summed over frames.
TEST(Aos, PerfectOrientationGivesApAndCurveAgreesWithAssociations) {
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

// A component with more distinct scores than the exact AOS bound (256): the similarity is sampled at
// 64 scores, the lowest included, so the last curve point is still exact.
TEST(Aos, HugeComponentIsSampledAndExactAtTheLowestScore) {
  EvalFrame f;
  for (int i = 0; i < 3; ++i) f.labels.push_back(Car2D(10.0 * i, 0, 100 + 10.0 * i, 100, 0.1 * i));
  for (int k = 0; k < 400; ++k) {
    const double shift = (k % 21) - 10.0;
    f.detections.push_back(Car2D(shift, 0, 100 + shift, 100, 0.01 * (k % 50), 1.0 - k / 1000.0));
  }
  EvalOptions options = CarModerate2D(Matcher::kOptimal);
  options.classes[0].min_overlap = {0.5, 0.5, 0.5};
  const EvalResult result = Evaluate({f}, options);
  const ClassResult& r = result.results.at(0);
  ASSERT_FALSE(r.curve.empty());
  EXPECT_EQ(r.curve.back().tp, 3);
  const ClassFrame cf = PrepareClassFrame(f, options.classes[0], OverlapKind::k2D);
  const FrameAssociation a = Associate(Matcher::kOptimal, cf, Difficulty::kModerate, r.curve.back().threshold);
  double similarity = 0.0;
  for (int i = 0; i < cf.num_labels(); ++i) {
    ASSERT_EQ(a.label_outcome[i], Outcome::kTp);
    similarity += (1 + std::cos(cf.det_alpha[a.label_det[i]] - cf.label_alpha[i])) / 2;
  }
  EXPECT_NEAR(r.curve.back().similarity, similarity, 1e-9);
  EXPECT_LE(r.aos_r40, r.ap_r40 + 1e-9);
}

// Curves under a filter, by hand: a passing pair (score 0.8) and a label of 9900 px^2 matched by a
// detection of 10100 px^2 (score 0.9) under min-area=10000. Naive: the 0.9 detection is a FP, so
// precision is 0 then 1/2 at recall 1: AP_R40 50. Stable: the failing pair drops out: AP_R40 100.
TEST(FilteredCurves, ExactMatchersByHand) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 99, 100, 0), Car2D(300, 0, 500, 100, 0)};
  f.detections = {Car2D(0, 0, 101, 100, 0, 0.9), Car2D(300, 0, 500, 100, 0, 0.8)};
  for (Matcher m : {Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options = CarModerate2D(m);
    options.filter.conditions = ParseFilterConditions("min-area=10000");
    const EvalResult result = Evaluate({f}, options);
    const ClassResult& r = result.results.at(0);
    ASSERT_TRUE(r.filtered.has_value());
    const FilteredStats& fs = *r.filtered;
    ASSERT_EQ(fs.naive_curve.curve.size(), 2u) << MatcherName(m);
    EXPECT_EQ(fs.naive_curve.curve[0].fp, 1);
    EXPECT_EQ(fs.naive_curve.curve[1].tp, 1);
    EXPECT_NEAR(fs.naive_curve.ap_r40, 50.0, 1e-9) << MatcherName(m);
    EXPECT_NEAR(fs.stable_curve.ap_r40, 100.0, 1e-9) << MatcherName(m);
    EXPECT_NEAR(fs.stable_curve.aos_r40, 100.0, 1e-9) << MatcherName(m);
    ASSERT_EQ(fs.stable_curve.curve.size(), 1u);  // nothing counts at 0.9
    EXPECT_EQ(fs.stable_curve.curve[0].tp, 1);
    EXPECT_EQ(fs.stable_curve.curve[0].fp, 0);
    EXPECT_EQ(fs.stable_curve.curve[0].fn, 0);
    EXPECT_NEAR(r.ap_r40, 100.0, 1e-9);  // unfiltered: both pairs
  }
  // KITTI matcher, stable: the unfiltered thresholds (0.9 and 0.8); at 0.9 nothing counts (0 / 0),
  // at 0.8 the passing pair.
  EvalOptions options = CarModerate2D(Matcher::kKitti);
  options.filter.conditions = ParseFilterConditions("min-area=10000");
  const EvalResult result = Evaluate({f}, options);
  const FilteredStats& fs = *result.results.at(0).filtered;
  ASSERT_EQ(fs.stable_curve.curve.size(), 2u);
  EXPECT_EQ(fs.stable_curve.curve[0].tp + fs.stable_curve.curve[0].fp, 0);
  EXPECT_EQ(fs.stable_curve.curve[1].tp, 1);
  EXPECT_EQ(fs.stable_curve.curve[1].fp, 0);
  ASSERT_EQ(fs.naive_curve.curve.size(), 1u);  // one label left, one threshold (0.8)
  EXPECT_EQ(fs.naive_curve.curve[0].tp, 1);
  EXPECT_EQ(fs.naive_curve.curve[0].fp, 1);
}

// The mirror case: the label passes (10100 px^2) and its detection fails (9900 px^2). Naive: the
// label is missed (FN); stable: the pair drops out, nothing counts. Every matcher, curve and
// operating point.
TEST(FilteredCurves, PassingLabelWithFailingDetectionDropsOutWhenStable) {
  EvalFrame f;
  f.labels = {Car2D(0, 0, 101, 100, 0), Car2D(300, 0, 500, 100, 0)};
  f.detections = {Car2D(0, 0, 99, 100, 0, 0.9), Car2D(300, 0, 500, 100, 0, 0.8)};
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options = CarModerate2D(m);
    options.filter.conditions = ParseFilterConditions("min-area=10000");
    const EvalResult result = Evaluate({f}, options);
    const FilteredStats& fs = *result.results.at(0).filtered;
    EXPECT_EQ(fs.stable.tp, 1) << MatcherName(m);
    EXPECT_EQ(fs.stable.fn, 0) << MatcherName(m);
    EXPECT_EQ(fs.naive.fn, 1) << MatcherName(m);
    ASSERT_FALSE(fs.stable_curve.curve.empty());
    EXPECT_EQ(fs.stable_curve.curve.back().tp, 1) << MatcherName(m);
    EXPECT_EQ(fs.stable_curve.curve.back().fn, 0) << MatcherName(m);
    EXPECT_EQ(fs.naive_curve.curve.back().fn, 1) << MatcherName(m);
    if (m != Matcher::kKitti) {
      EXPECT_NEAR(fs.stable_curve.ap_r40, 100.0, 1e-9) << MatcherName(m);
      EXPECT_NEAR(fs.naive_curve.ap_r40, 50.0, 1e-9) << MatcherName(m);  // recall 1/2 at precision 1
    }
  }
}

// Properties on random frames, every matcher: a filter everything passes leaves the curves and AP
// unchanged in both modes; and under a real filter, each mode's curve at the operating threshold
// has the counts of that mode's operating point.
TEST(FilteredCurves, AgreeWithUnfilteredAndWithTheOperatingPoint) {
  RandomFramesOptions ro;
  ro.num_frames = 30;
  ro.crowded = true;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (Matcher m : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    EvalOptions options;
    options.matcher = m;
    options.metrics = {OverlapKind::k2D, OverlapKind::kBev};
    options.filter.conditions = ParseFilterConditions("min-area=0");
    const EvalResult all_pass = Evaluate(frames, options);
    for (const ClassResult& r : all_pass.results) {
      if (!r.evaluated) continue;
      for (const FilteredCurve* c : {&r.filtered->naive_curve, &r.filtered->stable_curve}) {
        EXPECT_NEAR(c->ap_r40, r.ap_r40, 1e-9) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_NEAR(c->ap_r11, r.ap_r11, 1e-9) << MatcherName(m) << ' ' << r.class_name;
        ASSERT_EQ(c->curve.size(), r.curve.size()) << MatcherName(m) << ' ' << r.class_name;
        for (size_t k = 0; k < r.curve.size(); ++k) {
          EXPECT_EQ(c->curve[k].tp, r.curve[k].tp);
          EXPECT_EQ(c->curve[k].fp, r.curve[k].fp);
          EXPECT_EQ(c->curve[k].fn, r.curve[k].fn);
        }
      }
    }
    if (m == Matcher::kKitti) continue;  // its curve has only the devkit's thresholds
    options.filter.conditions = ParseFilterConditions("min-area=3000,max-distance=40");
    options.score_threshold = 0.5;
    const EvalResult filtered = Evaluate(frames, options);
    int nontrivial = 0;
    for (const ClassResult& r : filtered.results) {
      if (!r.evaluated) continue;
      auto at = [&](const FilteredCurve& c, const OperatingPoint& op) {
        CurvePoint p;
        p.fn = op.tp + op.fn;  // nothing detected above every threshold: all counted labels are FN
        for (const CurvePoint& q : c.curve) {
          if (q.threshold >= 0.5) p = q;
        }
        EXPECT_EQ(p.tp, op.tp) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_EQ(p.fp, op.fp) << MatcherName(m) << ' ' << r.class_name;
        EXPECT_EQ(p.fn, op.fn) << MatcherName(m) << ' ' << r.class_name;
      };
      at(r.filtered->naive_curve, r.filtered->naive);
      at(r.filtered->stable_curve, r.filtered->stable);
      nontrivial += r.filtered->stable.tp > 0 ? 1 : 0;
    }
    EXPECT_GT(nontrivial, 0);
  }
}

TEST(Filters, ParsesAndRejects) {
  const auto c = ParseFilterConditions("min-height=25, max-distance=40,difficulty=moderate");
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[2].bound, FilterBound::kDifficulty);
  EXPECT_EQ(c[2].value, 1);
  EXPECT_THROW(ParseFilterConditions("min-size=3"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area=abc"), std::invalid_argument);
  EXPECT_THROW(ParseFilterConditions("min-area"), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
