#include "stereodet/eval/openpcdet_compat.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/openpcdet_compat_internal.h"
#include "stereodet/kitti/label_io.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

EvalFrame Frame(const char* labels, const char* detections) {
  EvalFrame frame;
  frame.id = "000000";
  frame.labels = ParseObjects(labels, "label", {ObjectFileKind::kLabel}).objects;
  frame.detections = ParseObjects(detections, "det", {ObjectFileKind::kDetection}).objects;
  return frame;
}

EvalOptions Options(EvalCompat compat, const std::string& class_name = "Car") {
  EvalOptions options;
  options.compat = compat;
  options.classes = {compat == EvalCompat::kOpenPcdet ? OpenPcdetClassSpec(class_name)
                                                      : KittiClassSpec(class_name)};
  options.num_threads = 1;
  return options;
}

Object Footprint(double x, double z, double l, double w, double ry) {
  Object o;
  o.box3d.location = Eigen::Vector3d(x, 1.5, z);
  o.box3d.l = l;
  o.box3d.w = w;
  o.box3d.h = 1.5;
  o.box3d.rotation_y = ry;
  return o;
}

// get_official_eval_result's overlap_0_7 / overlap_0_5 tables, class by class.
TEST(OpenPcdetCompatTest, ClassSpecHasTheToolsOverlapsAndNeighbours) {
  EXPECT_EQ(OpenPcdetClassSpec("Car").min_overlap,
            (std::array<double, 5>{0.7, 0.7, 0.7, 0.7, 0.7}));
  EXPECT_EQ(OpenPcdetClassSpec("car", true).min_overlap,
            (std::array<double, 5>{0.7, 0.5, 0.5, 0.5, 0.5}));
  EXPECT_EQ(OpenPcdetClassSpec("Car").neighbours, std::vector<std::string>{"Van"});
  EXPECT_EQ(OpenPcdetClassSpec("Pedestrian", true).min_overlap,
            (std::array<double, 5>{0.5, 0.25, 0.25, 0.25, 0.25}));
  EXPECT_EQ(OpenPcdetClassSpec("Pedestrian").neighbours,
            std::vector<std::string>{"Person_sitting"});
  EXPECT_TRUE(OpenPcdetClassSpec("Cyclist").neighbours.empty());
  // Unlike KittiClassSpec (0.5 for any other class): Van and Truck are 0.7, and the loose Truck
  // is 0.5 in 2D too.
  EXPECT_EQ(OpenPcdetClassSpec("Van").min_overlap,
            (std::array<double, 5>{0.7, 0.7, 0.7, 0.7, 0.7}));
  EXPECT_EQ(OpenPcdetClassSpec("Truck", true).min_overlap,
            (std::array<double, 5>{0.5, 0.5, 0.5, 0.5, 0.5}));
  EXPECT_EQ(OpenPcdetClassSpec("Person_sitting", true).min_overlap,
            (std::array<double, 5>{0.5, 0.25, 0.25, 0.25, 0.25}));
  EXPECT_THROW(OpenPcdetClassSpec("Tram"), std::invalid_argument);
}

// Axis-aligned footprints: the float32 corners are exact, so the kernel's area is the true one.
TEST(OpenPcdetCompatTest, IntersectionAreaOfAxisAlignedBoxesIsExact) {
  const PcdetRotatedBox a{0, 10, 4, 2, 0}, b{2, 10, 4, 2, 0}, far{9, 10, 4, 2, 0};
  EXPECT_EQ(PcdetIntersectionArea(a, b), 4.0);
  EXPECT_EQ(PcdetIntersectionArea(a, far), 0.0);
  // BEV IoU 4 / (8 + 8 - 4), stored as float32.
  const Object g = Footprint(0, 10, 4, 2, 0), d = Footprint(2, 10, 4, 2, 0);
  EXPECT_EQ(PcdetOverlap(OverlapKind::kBev, d, g),
            static_cast<double>(static_cast<float>(1.0 / 3)));
}

// The kernel loses corners of identical footprints to float32 rounding. Expected values: what
// rotate_iou.py printed for these boxes under NUMBA_ENABLE_CUDASIM=1 (numba 0.56, numpy 1.24).
TEST(OpenPcdetCompatTest, IntersectionAreaOfIdenticalFootprintsAsTheKernelComputesIt) {
  struct Case {
    PcdetRotatedBox box;
    double iou;
  };
  const Case cases[] = {
      {{1.23, 20.5, 3.9, 1.6, -1.21}, 0.0},               // all area lost
      {{-4.5, 30.2, 4.2, 1.7, 1.57}, 0.0},                // all area lost
      {{2.0, 15.0, 4.0, 2.0, 0.79}, 0.3333333134651184},  // a triangle: half the box
      {{1.23, 20.5, 3.9, 1.6, 0.0}, 0.9999980330467224},  // all corners, float32 rounding
  };
  for (const Case& c : cases) {
    Object o = Footprint(c.box.x, c.box.z, c.box.l, c.box.w, c.box.rotation_y);
    EXPECT_EQ(PcdetOverlap(OverlapKind::kBev, o, o), c.iou) << c.box.rotation_y;
  }
  // Two nearby boxes: float32 rounding of a regular intersection.
  const Object g = Footprint(-4.5, 30.2, 4.2, 1.7, 0.3), d = Footprint(-4.4, 30.0, 4.0, 1.8, 0.35);
  EXPECT_EQ(PcdetOverlap(OverlapKind::kBev, d, g), 0.7765220403671265);
}

// 3D: the footprint intersection times the y overlap, over the volumes (l * h * w) minus it.
TEST(OpenPcdetCompatTest, OverlapIn3DIsFootprintTimesHeightOverlap) {
  Object g = Footprint(0, 10, 4, 2, 0), d = g;
  d.box3d.location.y() = 1.0;                            // 0.5 m higher: y overlap 1.0 of 1.5
  EXPECT_EQ(PcdetOverlap(OverlapKind::k3D, d, g), 0.5);  // 8 / (12 + 12 - 8)
  d.box3d.location.y() = -0.1;                           // no y overlap
  EXPECT_EQ(PcdetOverlap(OverlapKind::k3D, d, g), 0.0);
  // Identical boxes whose footprint the kernel loses have 3D overlap 0 too.
  const Object lost = Footprint(1.23, 20.5, 3.9, 1.6, -1.21);
  EXPECT_EQ(PcdetOverlap(OverlapKind::k3D, lost, lost), 0.0);
}

// clean_data: `height <= MIN_HEIGHT` ignores a label exactly 40 px tall at Easy.
TEST(OpenPcdetCompatTest, LabelExactlyAtTheMinimumHeightIsIgnored) {
  const EvalFrame frame =
      Frame("Car 0.00 0 0.00 100.00 100.00 200.00 140.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00\n",
            "Car -1 -1 0.00 100.00 100.00 200.00 140.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00 0.9\n");
  const ClassFrame cf =
      PrepareClassFrameOpenPcdet(frame, OpenPcdetClassSpec("Car"), OverlapKind::k2D);
  ASSERT_EQ(cf.num_labels(), 1);
  EXPECT_FALSE(cf.LabelValid(0, Difficulty::kEasy));
  EXPECT_TRUE(cf.LabelValid(0, Difficulty::kModerate));
  const EvalResult r = Evaluate({frame}, Options(EvalCompat::kOpenPcdet));
  EXPECT_EQ(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->num_valid_labels, 0);
  EXPECT_EQ(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->ap_r11, 0.0);
  EXPECT_NEAR(r.Find("Car", OverlapKind::k2D, Difficulty::kModerate)->ap_r11, 100.0 / 11, 1e-9);
}

// A detection without 3D (-1 / -1000, as a 2D detector writes it) in a frame with KITTI's DontCare
// row: the devkit's BEV DontCare test suppresses it (both are the 1 m square at (-1000, -1000)),
// OpenPCDet tests DontCare in 2D only, so it is a BEV false positive there. Scores 0.9 (TP) and
// 0.95 (the FP): one threshold, precision 1 or 1/2 in slot 0, AP_R11 = 100/11 or 50/11.
TEST(OpenPcdetCompatTest, DontCareSuppressesFalsePositivesIn2DOnly) {
  const EvalFrame frame = Frame(
      "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
      "DontCare -1 -1 -10 600.00 100.00 700.00 150.00 -1 -1 -1 -1000 -1000 -1000 -10\n",
      "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
      "Car -1 -1 -10 100.00 100.00 150.00 200.00 -1 -1 -1 -1000 -1000 -1000 -10 0.95\n");
  const EvalResult devkit = Evaluate({frame}, Options(EvalCompat::kDevkit));
  const EvalResult pcdet = Evaluate({frame}, Options(EvalCompat::kOpenPcdet));
  EXPECT_NEAR(devkit.Find("Car", OverlapKind::kBev, Difficulty::kEasy)->ap_r11, 100.0 / 11, 1e-9);
  EXPECT_NEAR(pcdet.Find("Car", OverlapKind::kBev, Difficulty::kEasy)->ap_r11, 50.0 / 11, 1e-9);
  EXPECT_NEAR(pcdet.Find("Car", OverlapKind::k3D, Difficulty::kEasy)->ap_r11, 50.0 / 11, 1e-9);

  // In 2D a detection inside the DontCare box is suppressed in both; OpenPCDet matches the name
  // "DontCare" exactly, the devkit case-insensitively.
  const char* dets =
      "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00 0.90\n"
      "Car -1 -1 0.00 610.00 100.00 690.00 150.00 1.70 1.60 3.90 -9.00 1.65 30.00 0.00 0.95\n";
  const EvalFrame dc = Frame(
      "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
      "DontCare -1 -1 -10 600.00 100.00 700.00 150.00 -1 -1 -1 -1000 -1000 -1000 -10\n",
      dets);
  const EvalFrame lower = Frame(
      "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.70 1.60 3.90 3.00 1.65 30.00 0.00\n"
      "dontcare -1 -1 -10 600.00 100.00 700.00 150.00 -1 -1 -1 -1000 -1000 -1000 -10\n",
      dets);
  for (const EvalCompat c : {EvalCompat::kDevkit, EvalCompat::kOpenPcdet}) {
    EXPECT_NEAR(Evaluate({dc}, Options(c)).Find("Car", OverlapKind::k2D, Difficulty::kEasy)->ap_r11,
                100.0 / 11, 1e-9);
  }
  EXPECT_NEAR(Evaluate({lower}, Options(EvalCompat::kDevkit))
                  .Find("Car", OverlapKind::k2D, Difficulty::kEasy)
                  ->ap_r11,
              100.0 / 11, 1e-9);
  EXPECT_NEAR(Evaluate({lower}, Options(EvalCompat::kOpenPcdet))
                  .Find("Car", OverlapKind::k2D, Difficulty::kEasy)
                  ->ap_r11,
              50.0 / 11, 1e-9);
}

// OpenPCDet looks at one alpha only: the first detection of the first frame with detections.
TEST(OpenPcdetCompatTest, AosIsDecidedByTheFirstDetection) {
  const char* labels =
      "Car 0.00 0 0.50 100.00 100.00 200.00 200.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00\n";
  const EvalFrame empty = Frame(labels, "");
  const EvalFrame valid =
      Frame(labels,
            "Car -1 -1 0.50 100.00 100.00 200.00 200.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00 0.9\n");
  const EvalFrame invalid =
      Frame(labels,
            "Car -1 -1 -10 100.00 100.00 200.00 200.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00 0.9\n");
  EXPECT_FALSE(OpenPcdetComputesAos({}));
  EXPECT_FALSE(OpenPcdetComputesAos({empty}));
  EXPECT_TRUE(OpenPcdetComputesAos({empty, valid, invalid}));
  EXPECT_FALSE(OpenPcdetComputesAos({empty, invalid, valid}));
  // The devkit turns AOS off for any alpha of -10.
  EXPECT_TRUE(Evaluate({empty, valid, invalid}, Options(EvalCompat::kOpenPcdet)).aos_computed);
  EXPECT_FALSE(Evaluate({empty, valid, invalid}, Options(EvalCompat::kDevkit)).aos_computed);
  EXPECT_TRUE(Evaluate({empty, valid}, Options(EvalCompat::kDevkit)).aos_computed);
  EXPECT_FALSE(Evaluate({invalid, valid}, Options(EvalCompat::kOpenPcdet)).aos_computed);
}

// OpenPCDet evaluates (and prints) every requested class, 0 where there is no detection of it; the
// devkit skips such a class.
TEST(OpenPcdetCompatTest, ClassWithoutDetectionsIsEvaluatedAsZero) {
  const EvalFrame frame =
      Frame("Cyclist 0.00 0 0.00 100.00 100.00 150.00 200.00 1.70 0.60 1.80 0.00 1.50 10.00 0.00\n",
            "Car -1 -1 0.00 300.00 100.00 400.00 200.00 1.50 1.60 3.90 3.00 1.50 10.00 0.00 0.9\n");
  EvalOptions devkit = Options(EvalCompat::kDevkit, "Cyclist");
  EvalOptions pcdet = Options(EvalCompat::kOpenPcdet, "Cyclist");
  EXPECT_FALSE(
      Evaluate({frame}, devkit).Find("Cyclist", OverlapKind::k2D, Difficulty::kEasy)->evaluated);
  const EvalResult pcdet_result = Evaluate({frame}, pcdet);  // r points into it
  const ClassResult* r = pcdet_result.Find("Cyclist", OverlapKind::kBev, Difficulty::kEasy);
  ASSERT_NE(r, nullptr);
  EXPECT_TRUE(r->evaluated);
  EXPECT_EQ(r->num_valid_labels, 1);
  EXPECT_EQ(r->ap_r40, 0.0);
  EXPECT_EQ(r->ap_r11, 0.0);
}

// np.max over slots i..40 is NaN if any of them is; the devkit's max_element loop skips a NaN that
// is not the first.
TEST(OpenPcdetCompatTest, EnvelopePropagatesNanToEarlierSlots) {
  std::array<double, 41> c{};
  c[0] = 0.25;
  c[1] = kNaN;
  c[2] = 0.5;
  c[3] = 1.0;
  c = OpenPcdetEnvelope(c);
  EXPECT_TRUE(std::isnan(c[0]));
  EXPECT_TRUE(std::isnan(c[1]));
  EXPECT_EQ(c[2], 1.0);
  EXPECT_EQ(c[3], 1.0);
  EXPECT_EQ(c[4], 0.0);
}

// Labels evaluated against themselves: 2D is perfect, BEV and 3D lose the footprints the kernel
// loses. Four cars, easy, scores 1: four thresholds of score 1, so a perfect 2D gives AP_R40 3/40.
TEST(OpenPcdetCompatTest, LabelsAgainstThemselvesLoseTheFootprintsTheKernelLoses) {
  const char* labels =
      "Car 0.00 0 0.00 100.00 100.00 200.00 200.00 1.50 1.60 3.90 1.23 1.50 20.50 -1.21\n"
      "Car 0.00 0 0.00 300.00 100.00 400.00 200.00 1.50 1.70 4.20 -4.50 1.50 30.20 1.57\n"
      "Car 0.00 0 0.00 500.00 100.00 600.00 200.00 1.50 2.00 4.00 2.00 1.50 15.00 0.79\n"
      "Car 0.00 0 0.00 700.00 100.00 800.00 200.00 1.50 1.60 3.90 1.23 1.50 20.50 0.00\n";
  std::string dets;
  for (const Object& o : ParseObjects(labels, "label", {ObjectFileKind::kLabel}).objects) {
    Object d = o;
    d.score = 1.0;
    dets += FormatObject(d) + "\n";
  }
  const EvalFrame frame = Frame(labels, dets.c_str());
  EvalOptions options = Options(EvalCompat::kOpenPcdet);
  const EvalResult r = Evaluate({frame}, options);
  EXPECT_NEAR(r.Find("Car", OverlapKind::k2D, Difficulty::kEasy)->ap_r40, 100.0 * 3 / 40, 1e-9);
  // BEV: only the last car's footprint survives (IoU 0.999998 > 0.7; the third keeps a third):
  // one TP, so one threshold (score 1), at which the three other detections are FPs: precision 1/4
  // in slot 0, AP_R11 = 25/11, AP_R40 = 0.
  const ClassResult* bev = r.Find("Car", OverlapKind::kBev, Difficulty::kEasy);
  EXPECT_NEAR(bev->ap_r11, 25.0 / 11, 1e-9);
  EXPECT_EQ(bev->ap_r40, 0.0);
  // The devkit's exact overlaps find all four.
  const EvalResult devkit = Evaluate({frame}, Options(EvalCompat::kDevkit));
  EXPECT_NEAR(devkit.Find("Car", OverlapKind::kBev, Difficulty::kEasy)->ap_r40, 100.0 * 3 / 40,
              1e-9);
}

TEST(OpenPcdetCompatTest, FormatResultPrintsLikeGetOfficialEvalResult) {
  const EvalFrame frame =
      Frame("Car 0.00 0 0.50 100.00 100.00 200.00 200.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00\n",
            "Car -1 -1 0.50 100.00 100.00 200.00 200.00 1.50 1.60 3.90 0.00 1.50 10.00 0.00 0.9\n");
  EvalOptions options;
  options.classes = {KittiClassSpec("Car")};
  const std::string text = OpenPcdetPrintout({frame}, options);
  const std::string expected =
      "Car AP@0.70, 0.70, 0.70:\n"
      "bbox AP:9.0909, 9.0909, 9.0909\n"
      "bev  AP:9.0909, 9.0909, 9.0909\n"
      "3d   AP:9.0909, 9.0909, 9.0909\n"
      "aos  AP:9.09, 9.09, 9.09\n"
      "Car AP_R40@0.70, 0.70, 0.70:\n"
      "bbox AP:0.0000, 0.0000, 0.0000\n"
      "bev  AP:0.0000, 0.0000, 0.0000\n"
      "3d   AP:0.0000, 0.0000, 0.0000\n"
      "aos  AP:0.00, 0.00, 0.00\n"
      "Car AP@0.70, 0.50, 0.50:\n"
      "bbox AP:9.0909, 9.0909, 9.0909\n"
      "bev  AP:9.0909, 9.0909, 9.0909\n"
      "3d   AP:9.0909, 9.0909, 9.0909\n"
      "aos  AP:9.09, 9.09, 9.09\n"
      "Car AP_R40@0.70, 0.50, 0.50:\n"
      "bbox AP:0.0000, 0.0000, 0.0000\n"
      "bev  AP:0.0000, 0.0000, 0.0000\n"
      "3d   AP:0.0000, 0.0000, 0.0000\n"
      "aos  AP:0.00, 0.00, 0.00\n";
  EXPECT_EQ(text, expected);
}

// tests/data/eval_small/openpcdet_expected.txt is what OpenPCDet's get_official_eval_result (commit
// 8cacccec, numba 0.56.4 CUDA simulator) printed for Car, Pedestrian and Cyclist on these frames.
TEST(OpenPcdetCompatTest, PrintoutEqualsTheToolsOnTheFixture) {
  namespace fs = std::filesystem;
  const fs::path dir = ::stereodet::TestSourceDir() / "tests/data/eval_small";
  std::vector<fs::path> labels;
  for (const auto& e : fs::directory_iterator(dir / "label_2")) labels.push_back(e.path());
  std::sort(labels.begin(), labels.end());
  std::vector<EvalFrame> frames;
  for (const fs::path& p : labels) {
    EvalFrame f;
    f.id = p.stem().string();
    f.labels = ReadObjects(p, {ObjectFileKind::kLabel, false}).objects;
    f.detections =
        ReadObjects(dir / "det" / p.filename(), {ObjectFileKind::kDetection, false}).objects;
    frames.push_back(std::move(f));
  }
  ASSERT_EQ(frames.size(), 12u);
  std::ifstream in(dir / "openpcdet_expected.txt");
  std::stringstream expected;
  expected << in.rdbuf();
  EvalOptions options;
  options.num_threads = 2;
  EXPECT_EQ(OpenPcdetPrintout(frames, options), expected.str());
}

}  // namespace
}  // namespace stereodet
