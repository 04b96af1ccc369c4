#include "stereodet/eval/let.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/frame_data.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

// A car 4 m long (along z: rotation_y = pi / 2), 1.6 m wide, 1.5 m high, its centre at (x, y, z).
Box3D Car(double x, double z, double y = 0.0) {
  Box3D box;
  box.h = 1.5;
  box.w = 1.6;
  box.l = 4.0;
  box.rotation_y = std::numbers::pi / 2;
  box.location = Eigen::Vector3d(x, y + box.h / 2, z);
  return box;
}

TEST(LetTest, IdenticalBoxesHaveAffinityAndOverlapOne) {
  const LetOptions options;
  const Box3D car = Car(2.0, 15.0);
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(car, car, options), 1.0);
  EXPECT_NEAR(LetOverlap(OverlapKind::kBev, car, car, options), 1.0, 1e-12);
  EXPECT_NEAR(LetOverlap(OverlapKind::k3D, car, car, options), 1.0, 1e-12);
}

// The example: a label 20 m straight ahead, a detection of the same size 1 m beyond it.
// Tolerance max(0.1 * 20, 0.5) = 2 m, error 1 m: affinity 1 - 1 / 2 = 0.5. Range-aligned, the
// detection lands on the label (LET-IoU 1), where plain 3D IoU is 3 / (4 + 1) = 0.6 (4 m boxes
// overlapping 3 m along their length).
TEST(LetTest, OneMetreBeyondALabelAtTwentyMetres) {
  const LetOptions options;
  const Box3D label = Car(0.0, 20.0);
  const Box3D detection = Car(0.0, 21.0);
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(detection, label, options), 0.5);
  EXPECT_NEAR(LetOverlap(OverlapKind::k3D, detection, label, options), 1.0, 1e-12);
  EXPECT_NEAR(LetOverlap(OverlapKind::kBev, detection, label, options), 1.0, 1e-12);
  EXPECT_NEAR(KittiBoxOverlap(OverlapKind::k3D, detection, label), 0.6, 1e-12);
  const Box3D aligned = RangeAlignedBox(detection, label, options);
  EXPECT_NEAR(aligned.location.z(), 20.0, 1e-12);
  EXPECT_NEAR(aligned.location.y(), label.location.y(), 1e-12);
  EXPECT_EQ(aligned.l, detection.l);
  EXPECT_EQ(aligned.rotation_y, detection.rotation_y);
  // Nearer by 1 m: the same affinity (the error's sign does not matter).
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(Car(0.0, 19.0), label, options), 0.5);
  // 3 m beyond: outside the 2 m tolerance, affinity 0 (no match however large the LET-IoU).
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(Car(0.0, 23.0), label, options), 0.0);
  EXPECT_NEAR(LetOverlap(OverlapKind::k3D, Car(0.0, 23.0), label, options), 1.0, 1e-12);
}

// Near the sensor the minimum tolerance holds: a label at 3 m has max(0.3, 0.5) = 0.5 m, so 0.25 m
// of error leaves affinity 0.5.
TEST(LetTest, MinimumToleranceNearTheSensor) {
  const LetOptions options;
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(Car(0.0, 3.25), Car(0.0, 3.0), options), 0.5);
  LetOptions tight;
  tight.min_longitudinal_tolerance_m = 0.0;  // 0.3 m: 1 - 0.25 / 0.3
  EXPECT_NEAR(LongitudinalAffinity(Car(0.0, 3.25), Car(0.0, 3.0), tight), 1 - 0.25 / 0.3, 1e-12);
}

// LET forgives range, not lateral error: a detection 1 m to the side of a label 20 m ahead has no
// range error (affinity 1), and range alignment moves it along its own line of sight only, to
// t = 400 / 401 of its centre: 0.997506 m to the side and 0.049875 m nearer. BEV overlap by hand:
// (1.6 - dx) (4 - dz) / (2 * 6.4 - (1.6 - dx) (4 - dz)).
TEST(LetTest, LateralErrorIsNotForgiven) {
  const LetOptions options;
  const Box3D label = Car(0.0, 20.0);
  const Box3D detection = Car(1.0, 20.0);
  EXPECT_DOUBLE_EQ(LongitudinalAffinity(detection, label, options), 1.0);
  const double t = 400.0 / 401.0;
  const double dx = t * 1.0, dz = 20.0 - t * 20.0;
  const double inter = (1.6 - dx) * (4.0 - dz);
  EXPECT_NEAR(LetOverlap(OverlapKind::kBev, detection, label, options),
              inter / (2 * 1.6 * 4.0 - inter), 1e-12);
  EXPECT_LT(LetOverlap(OverlapKind::kBev, detection, label, options), 0.25);
}

// The sensor's position: with the sensor 1 m to the right of a label 20 m ahead, the label's line
// of sight is tilted, and a detection 1 m beyond the label along the camera's z axis has error
// (P . G) / |G| - |G| with P = (-1, 0, 21), G = (-1, 0, 20) relative to the sensor.
TEST(LetTest, SensorPositionSetsTheLineOfSight) {
  LetOptions options;
  options.sensor_m = Eigen::Vector3d(1.0, 0.0, 0.0);
  const double g = std::sqrt(401.0);
  const double error = (1.0 + 420.0) / g - g;
  EXPECT_NEAR(LongitudinalAffinity(Car(0.0, 21.0), Car(0.0, 20.0), options), 1 - error / (0.1 * g),
              1e-12);
}

// Random boxes: (1) the aligned centre is the point of the detection's line of sight closest to the
// label's centre (no t nearby does better); (2) along the label's line of sight, affinity is
// max(0, 1 - |e| / tolerance) for a displacement e; (3) a displacement perpendicular to the label's
// line of sight leaves the affinity alone; (4) moving the sensor and every box by the same vector
// changes nothing.
TEST(LetTest, PropertiesOnRandomBoxes) {
  std::mt19937 rng(36);
  std::uniform_real_distribution<double> xy(-10.0, 10.0), z(1.0, 70.0), unit(-1.0, 1.0),
      size(0.5, 5.0), angle(-std::numbers::pi, std::numbers::pi);
  auto random_box = [&] {
    Box3D b;
    b.h = size(rng);
    b.w = size(rng);
    b.l = size(rng);
    b.rotation_y = angle(rng);
    b.location = Eigen::Vector3d(xy(rng), xy(rng) / 5, z(rng));
    return b;
  };
  for (int trial = 0; trial < 500; ++trial) {
    LetOptions options;
    options.sensor_m = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    const Box3D label = random_box();
    const Box3D detection = random_box();
    const Eigen::Vector3d g = label.Centre() - options.sensor_m;
    const Eigen::Vector3d p = detection.Centre() - options.sensor_m;
    // (1)
    const Eigen::Vector3d aligned = RangeAlignedBox(detection, label, options).Centre();
    const double best = (aligned - label.Centre()).norm();
    const double t = (aligned - options.sensor_m).norm() / p.norm();
    for (double step : {-1e-3, 1e-3, -0.1, 0.1}) {
      const double other = (options.sensor_m + (t + step) * p - label.Centre()).norm();
      EXPECT_LE(best, other + 1e-9) << "trial " << trial;
    }
    // (2)
    const double tolerance = std::max(0.1 * g.norm(), 0.5);
    const double e = unit(rng) * 3 * tolerance;
    Box3D along = label;
    along.location += e * g.normalized();
    EXPECT_NEAR(LongitudinalAffinity(along, label, options),
                std::max(0.0, 1 - std::abs(e) / tolerance), 1e-9)
        << "trial " << trial;
    // (3)
    const Eigen::Vector3d side = g.cross(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    Box3D beside = detection;
    beside.location += side.normalized() * 2 * unit(rng);
    const Eigen::Vector3d moved = beside.Centre() - options.sensor_m;
    EXPECT_NEAR(moved.dot(g), p.dot(g), 1e-7 * (1 + std::abs(p.dot(g))));
    EXPECT_NEAR(LongitudinalAffinity(beside, label, options),
                LongitudinalAffinity(detection, label, options), 1e-9);
    // (4)
    const Eigen::Vector3d shift(xy(rng), xy(rng), xy(rng));
    LetOptions shifted = options;
    shifted.sensor_m += shift;
    Box3D d2 = detection, l2 = label;
    d2.location += shift;
    l2.location += shift;
    EXPECT_NEAR(LongitudinalAffinity(d2, l2, shifted),
                LongitudinalAffinity(detection, label, options), 1e-9);
    EXPECT_NEAR(LetOverlap(OverlapKind::k3D, d2, l2, shifted),
                LetOverlap(OverlapKind::k3D, detection, label, options), 1e-9);
  }
}

// Waymo Open Dataset's own implementation (its ComputeLetIoU, range-aligned, for 3D and BEV boxes,
// and ComputeLongitudinalAffinity, at 10 % and 0.5 m) on 400 random pairs in KITTI's frame with
// random sensor positions: tests/data/let/waymo_cases.csv, written by
// scripts/let_reference_cases.py from a program linked against Waymo's metrics code
// (docs/metrics.md, "LET-3D-AP"). Waymo keeps the tolerance in float (its 0.1 is 0.1f), hence 1e-6
// on the affinity; the overlaps are both double-precision polygon clipping.
TEST(LetTest, WaymoReferenceCases) {
  std::ifstream in(TestSourceDir() / "tests/data/let/waymo_cases.csv");
  ASSERT_TRUE(in) << "tests/data/let/waymo_cases.csv";
  const LetOptions defaults;
  std::string line;
  int cases = 0, matched = 0, header = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header++ == 0) continue;
    std::vector<double> v;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(std::stod(field));
    ASSERT_EQ(v.size(), 20u) << line;
    auto box = [&](int at) {
      Box3D b;
      b.h = v[at];
      b.w = v[at + 1];
      b.l = v[at + 2];
      b.location = Eigen::Vector3d(v[at + 3], v[at + 4], v[at + 5]);
      b.rotation_y = v[at + 6];
      return b;
    };
    const Box3D label = box(0), detection = box(7);
    LetOptions options = defaults;
    options.sensor_m = Eigen::Vector3d(v[14], v[15], v[16]);
    EXPECT_NEAR(LetOverlap(OverlapKind::k3D, detection, label, options), v[17], 1e-9)
        << "case " << cases;
    EXPECT_NEAR(LetOverlap(OverlapKind::kBev, detection, label, options), v[18], 1e-9)
        << "case " << cases;
    EXPECT_NEAR(LongitudinalAffinity(detection, label, options), v[19], 1e-6) << "case " << cases;
    matched += v[19] > 0 && v[17] >= 0.5;
    ++cases;
  }
  EXPECT_EQ(cases, 400);
  EXPECT_GT(matched, 100);  // the set exercises matches, not only misses
}

// Whole frames through the evaluator against Waymo's whole metric (tests/data/let/waymo_frames.csv,
// scripts/let_reference_cases.py --frames-out: 150 frames, 327 cars, 515 detections; Waymo's
// Hungarian matcher, IoU >= 0.5, LET at 10 % and 0.5 m): at each score cutoff, the LET-3D and
// LET-BEV cells' TP, FP and FN and the sum of the TPs' affinities (LET-APL's numerator) under the
// optimal matcher. Cars here stand apart, as cars do, so the most true positives (stereodet's
// first aim) and the largest total LET-IoU x affinity (Waymo's only aim) pick the same pairs. The
// areas (AP, APL) are not compared: Waymo integrates its own way (docs/metrics.md).
TEST(LetTest, WaymoReferenceFrames) {
  std::ifstream in(TestSourceDir() / "tests/data/let/waymo_frames.csv");
  ASSERT_TRUE(in) << "tests/data/let/waymo_frames.csv";
  std::vector<EvalFrame> frames;
  struct Counts {
    int64_t tp, fp, fn;
    double sum_affinity;
  };
  std::map<std::pair<std::string, int>, Counts> expected;  // (box type, cutoff x 20)
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) f.push_back(field);
    if (f.size() == 7 && f[1] == "counts") {
      const int cutoff = static_cast<int>(std::lround(std::stod(f[2]) * 20));
      expected[{f[0], cutoff}] = {std::stoll(f[3]), std::stoll(f[4]), std::stoll(f[5]),
                                  std::stod(f[6])};
      continue;
    }
    ASSERT_GE(f.size(), 9u) << line;
    const size_t k = std::stoul(f[0]);
    if (frames.size() <= k) frames.resize(k + 1);
    Object o;
    o.type = "Car";
    o.box = {100, 100, 200, 200};  // tall, untruncated, unoccluded: a valid Easy label
    o.box3d.h = std::stod(f[2]);
    o.box3d.w = std::stod(f[3]);
    o.box3d.l = std::stod(f[4]);
    o.box3d.location = Eigen::Vector3d(std::stod(f[5]), std::stod(f[6]), std::stod(f[7]));
    o.box3d.rotation_y = std::stod(f[8]);
    if (f[1] == "det") {
      o.score = std::stod(f.at(9));
      frames[k].detections.push_back(o);
    } else {
      frames[k].labels.push_back(o);
    }
  }
  ASSERT_EQ(frames.size(), 150u);
  ASSERT_EQ(expected.size(), 40u);
  EvalOptions options;
  options.classes = {KittiClassSpec("Car", /*loose=*/true)};  // LET-BEV and LET-3D at 0.5
  options.metrics = {OverlapKind::kLet3D, OverlapKind::kLetBev};
  options.difficulties = {Difficulty::kEasy};
  options.matcher = Matcher::kOptimal;
  const EvalResult result = Evaluate(frames, options);
  int checked = 0;
  for (const auto& [key, want] : expected) {
    const auto& [box_type, cutoff] = key;
    const OverlapKind kind = box_type == "3d" ? OverlapKind::kLet3D : OverlapKind::kLetBev;
    const ClassResult& r = *result.Find("Car", kind, Difficulty::kEasy);
    ASSERT_EQ(r.num_valid_labels, 327);
    // The curve's point at the lowest score >= the cutoff (scores are on the same 0.05 grid).
    CurvePoint at;
    at.fn = r.num_valid_labels;
    for (const CurvePoint& p : r.curve) {
      if (p.threshold >= cutoff * 0.05 - 1e-9) at = p;
    }
    SCOPED_TRACE(box_type + " cutoff " + std::to_string(cutoff * 0.05));
    EXPECT_EQ(at.tp, want.tp);
    EXPECT_EQ(at.fp, want.fp);
    EXPECT_EQ(at.fn, want.fn);
    EXPECT_NEAR(at.similarity, want.sum_affinity, 1e-4);  // Waymo sums floats
    ++checked;
  }
  EXPECT_EQ(checked, 40);
  EXPECT_GT(result.Find("Car", OverlapKind::kLet3D, Difficulty::kEasy)->at_threshold.tp, 150);
}

TEST(LetTest, OptionsAreChecked) {
  LetOptions options;
  EXPECT_NO_THROW(options.Check());
  options.longitudinal_tolerance_fraction = -0.1;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options.longitudinal_tolerance_fraction = 0.0;
  options.min_longitudinal_tolerance_m = 0.0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options.min_longitudinal_tolerance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = LetOptions();
  options.sensor_m.x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(options.Check(), std::invalid_argument);
  EXPECT_THROW(LetOverlap(OverlapKind::k2D, Car(0, 10), Car(0, 10), LetOptions()),
               std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
