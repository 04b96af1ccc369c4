// GT-database cut-and-paste: hand-checked cuts (grown boxes, sparse objects left out), collision
// rejection against the frame's boxes and earlier pastes, point removal, per-class counts and
// determinism; invariants on random scenes against PointInBox.
#include "stereodet/models/det3d/gt_database.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>

namespace stereodet {
namespace {

LidarBox Car(double x, double y, double yaw = 0.0) {
  return {.x = x, .y = y, .z = -1.0, .l = 3.9, .w = 1.6, .h = 1.5, .yaw = yaw, .label = 0};
}
LidarBox Pedestrian(double x, double y) {
  return {.x = x, .y = y, .z = -0.9, .l = 0.8, .w = 0.6, .h = 1.7, .yaw = 0.0, .label = 1};
}

// `n` points spread inside the box (a 0.9 fraction of each extent), reflectance `r`.
void FillBox(const LidarBox& b, int n, float r, std::vector<VeloPoint>& points) {
  std::mt19937 rng(n * 31 + static_cast<int>(b.x * 7));
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  for (int i = 0; i < n; ++i) {
    const double along = u(rng) * b.l, across = u(rng) * b.w;
    points.push_back({static_cast<float>(b.x + std::cos(b.yaw) * along - std::sin(b.yaw) * across),
                      static_cast<float>(b.y + std::sin(b.yaw) * along + std::cos(b.yaw) * across),
                      static_cast<float>(b.z + u(rng) * b.h), r});
  }
}

Det3dFrame FrameWith(const std::string& id, const std::vector<LidarBox>& boxes, int points_each,
                     float reflectance) {
  Det3dFrame f;
  f.id = id;
  f.boxes = boxes;
  for (const LidarBox& b : boxes) FillBox(b, points_each, reflectance, f.points);
  return f;
}

TEST(GtDatabaseTest, CutsThePointsOfTheGrownBoxAndLeavesSparseObjectsOut) {
  Det3dFrame f;
  f.id = "000007";
  const LidarBox car = Car(10.0, 2.0, 0.3);
  f.boxes = {car, Pedestrian(20.0, -3.0), Car(30.0, 0.0)};
  FillBox(f.boxes[0], 12, 0.5f, f.points);
  FillBox(f.boxes[1], 6, 0.6f, f.points);
  FillBox(f.boxes[2], 4, 0.7f, f.points);  // 4 < min_points 5: left out
  // Along the car's heading: 0.1 m past its front face (inside the 0.2 m margin), 0.3 m past it
  // (outside); 0.15 m under its bottom face (inside).
  const double c = std::cos(0.3), s = std::sin(0.3);
  for (double along : {3.9 / 2 + 0.1, 3.9 / 2 + 0.3}) {
    f.points.push_back(
        {static_cast<float>(10.0 + c * along), static_cast<float>(2.0 + s * along), -1.0f, 0.9f});
  }
  f.points.push_back({10.0f, 2.0f, static_cast<float>(-1.0 - 0.75 - 0.15), 0.9f});
  f.points.push_back({40.0f, 5.0f, -1.0f, 0.9f});  // in no box

  const GtDatabase db = BuildGtDatabase({f}, 2, PointSource::kStereo, {});
  EXPECT_EQ(db.source, PointSource::kStereo);
  ASSERT_EQ(db.objects_by_class.size(), 2u);
  ASSERT_EQ(db.objects_by_class[0].size(), 1u);
  ASSERT_EQ(db.objects_by_class[1].size(), 1u);
  EXPECT_EQ(db.ObjectCount(), 2);
  const GtObject& o = db.objects_by_class[0][0];
  EXPECT_EQ(o.box, car);
  EXPECT_EQ(o.frame_id, "000007");
  EXPECT_EQ(o.points.size(), 12u + 2u);  // its own 12, the one 0.1 m ahead, the one below
  EXPECT_EQ(db.objects_by_class[1][0].points.size(), 6u);
  EXPECT_EQ(db.PointCount(), 20);

  // No margin: only the 12; min_points 13 leaves the car out too.
  GtDatabaseOptions tight;
  tight.box_margin_m = 0.0;
  EXPECT_EQ(
      BuildGtDatabase({f}, 2, PointSource::kLidar, tight).objects_by_class[0][0].points.size(),
      12u);
  tight.min_points = 13;
  EXPECT_EQ(BuildGtDatabase({f}, 2, PointSource::kLidar, tight).ObjectCount(), 0);

  GtDatabaseOptions bad;
  bad.min_points = 0;
  EXPECT_THROW(BuildGtDatabase({f}, 2, PointSource::kLidar, bad), std::invalid_argument);
  EXPECT_THROW(BuildGtDatabase({f}, 1, PointSource::kLidar, {}), std::invalid_argument);  // label 1
}

TEST(GtDatabaseTest, CutMatchesPointInBoxOnRandomScenes) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Det3dFrame f;
    for (int b = 0; b < 4; ++b) {
      f.boxes.push_back(Car(5 + 20 * u(rng), -8 + 16 * u(rng), 6.3 * u(rng)));
    }
    for (int i = 0; i < 3000; ++i) {
      f.points.push_back({static_cast<float>(3 + 24 * u(rng)),
                          static_cast<float>(-10 + 20 * u(rng)),
                          static_cast<float>(-2.5 + 3 * u(rng)), 0.1f});
    }
    GtDatabaseOptions options;
    options.box_margin_m = 0.3 * u(rng);
    options.min_points = 1;
    const GtDatabase db = BuildGtDatabase({f}, 1, PointSource::kLidar, options);
    size_t next = 0;
    for (const LidarBox& b : f.boxes) {
      const LidarBox grown = GrownBox(b, options.box_margin_m);
      std::vector<VeloPoint> expected;
      for (const VeloPoint& p : f.points) {
        if (PointInBox(grown, p.x, p.y, p.z)) expected.push_back(p);
      }
      if (expected.empty()) continue;
      ASSERT_LT(next, db.objects_by_class[0].size());
      const GtObject& o = db.objects_by_class[0][next++];
      EXPECT_EQ(o.box, b);
      ASSERT_EQ(o.points.size(), expected.size()) << "trial " << trial;
      for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ(o.points[i].x, expected[i].x);
        EXPECT_EQ(o.points[i].y, expected[i].y);
      }
    }
    EXPECT_EQ(next, db.objects_by_class[0].size());
  }
}

// The database: three cars side by side at x = 10 (y = -8, 0, 8; 20 points each, reflectance 0.5)
// and two pedestrians (10 points each, 0.6), cut from two frames.
GtDatabase HandDatabase() {
  Det3dFrame a, b;
  a.id = "a";
  a.boxes = {Car(10, -8), Car(10, 0), Pedestrian(20, 5)};
  b.id = "b";
  b.boxes = {Car(10, 8), Pedestrian(25, -5)};
  for (Det3dFrame* f : {&a, &b}) {
    for (const LidarBox& box : f->boxes) {
      FillBox(box, box.label == 0 ? 20 : 10, box.label == 0 ? 0.5f : 0.6f, f->points);
    }
  }
  return BuildGtDatabase({a, b}, 2, PointSource::kLidar, {});
}

TEST(GtDatabaseTest, PastesWhatDoesNotCollideRemovesTheFramePointsItCovers) {
  const GtDatabase db = HandDatabase();
  ASSERT_EQ(db.objects_by_class[0].size(), 3u);
  ASSERT_EQ(db.objects_by_class[1].size(), 2u);
  // The frame: one car at (10, 0.5), overlapping the database's car at (10, 0); three points:
  // one where the car at (10, -8) would go, one in the frame's car, one far from everything.
  Det3dFrame frame;
  frame.id = "target";
  frame.boxes = {Car(10, 0.5)};
  frame.points = {{10.0f, -8.0f, -1.0f, 0.1f}, {10.0f, 0.5f, -1.0f, 0.1f}, {40, 0, -1, 0.1f}};
  GtSamplingOptions options;
  options.max_per_class = 3;  // every car is drawn
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const GtSamplingResult r = SampleGtObjects(frame, db, options, seed);
    ASSERT_EQ(r.pasted_per_class.size(), 2u);
    EXPECT_EQ(r.pasted_per_class[0], 2) << "seed " << seed;  // the cars at y = -8 and 8
    EXPECT_EQ(r.pasted_per_class[1], 2);                     // both pedestrians
    EXPECT_EQ(r.rejected, 1);                                // the car at y = 0
    EXPECT_EQ(r.removed_points, 1);                          // the point at (10, -8)
    ASSERT_EQ(r.frame.boxes.size(), 5u);
    EXPECT_EQ(r.frame.boxes[0], frame.boxes[0]);  // the frame's own first
    std::set<double> car_y;
    for (size_t k = 1; k < 5; ++k) {
      if (r.frame.boxes[k].label == 0) car_y.insert(r.frame.boxes[k].y);
    }
    EXPECT_EQ(car_y, (std::set<double>{-8.0, 8.0}));
    // 2 frame points kept, then 20 + 20 + 10 + 10 pasted ones.
    ASSERT_EQ(r.frame.points.size(), 2u + 60u);
    EXPECT_EQ(r.frame.points[0].y, 0.5f);
    EXPECT_EQ(r.frame.points[1].x, 40.0f);
    EXPECT_EQ(r.frame.id, "target");
  }
  // K = 1: one car drawn a frame; the one at y = 0 always collides.
  options.max_per_class = 1;
  std::set<double> chosen;
  for (uint64_t seed = 0; seed < 30; ++seed) {
    const GtSamplingResult r = SampleGtObjects(frame, db, options, seed);
    EXPECT_EQ(r.pasted_per_class[0] + r.rejected, 1);
    EXPECT_EQ(r.pasted_per_class[1], 1);
    for (size_t k = 1; k < r.frame.boxes.size(); ++k) {
      if (r.frame.boxes[k].label == 0) chosen.insert(r.frame.boxes[k].y);
    }
  }
  EXPECT_EQ(chosen, (std::set<double>{-8.0, 8.0}));  // both, over the seeds
  // K = 0: the frame as it was.
  options.max_per_class = 0;
  const GtSamplingResult none = SampleGtObjects(frame, db, options, 5);
  EXPECT_EQ(none.frame.boxes, frame.boxes);
  EXPECT_EQ(none.frame.points.size(), 3u);
  EXPECT_EQ(none.removed_points, 0);
}

TEST(GtDatabaseTest, PastedObjectsDoNotCollideWithEachOther) {
  // Two cars of two frames at nearly the same place: only one can be pasted.
  const GtDatabase db = BuildGtDatabase(
      {FrameWith("a", {Car(12, 3)}, 10, 0.5f), FrameWith("b", {Car(12.5, 3.2, 0.2)}, 10, 0.5f)}, 1,
      PointSource::kLidar, {});
  ASSERT_EQ(db.ObjectCount(), 2);
  std::set<double> first;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const GtSamplingResult r = SampleGtObjects(Det3dFrame{}, db, {}, seed);
    EXPECT_EQ(r.pasted_per_class[0], 1);
    EXPECT_EQ(r.rejected, 1);
    ASSERT_EQ(r.frame.boxes.size(), 1u);
    EXPECT_EQ(r.frame.points.size(), 10u);
    first.insert(r.frame.boxes[0].x);
  }
  EXPECT_EQ(first.size(), 2u);  // the draw order depends on the seed
  // The grown boxes count: two cars 0.3 m apart side by side do not overlap, their grown boxes do.
  const GtDatabase close = BuildGtDatabase(
      {FrameWith("a", {Car(12, 0)}, 10, 0.5f), FrameWith("b", {Car(12, 1.9)}, 10, 0.5f)}, 1,
      PointSource::kLidar, {});
  EXPECT_EQ(LidarBevIou(Car(12, 0), Car(12, 1.9)), 0.0);
  EXPECT_EQ(SampleGtObjects(Det3dFrame{}, close, {}, 1).pasted_per_class[0], 1);
}

TEST(GtDatabaseTest, DeterministicFromTheSeedAndInvariantsHoldOnRandomScenes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto random_frame = [&](const std::string& id) {
    std::vector<LidarBox> boxes;
    for (int k = 0; k < 3; ++k) {
      const LidarBox b = Car(5 + 25 * u(rng), -10 + 20 * u(rng), 6.3 * u(rng));
      bool free = true;
      for (const LidarBox& o : boxes)
        free = free && LidarBevIou(GrownBox(b, 0.2), GrownBox(o, 0.2)) == 0;
      if (free) boxes.push_back(b);
    }
    Det3dFrame f = FrameWith(id, boxes, 30, 0.5f);
    for (int i = 0; i < 400; ++i) {  // ground
      f.points.push_back({static_cast<float>(3 + 30 * u(rng)),
                          static_cast<float>(-12 + 24 * u(rng)), -1.75f, 0.2f});
    }
    return f;
  };
  std::vector<Det3dFrame> frames;
  for (int i = 0; i < 8; ++i) frames.push_back(random_frame("f" + std::to_string(i)));
  const GtDatabase db = BuildGtDatabase(frames, 1, PointSource::kLidar, {});
  GtSamplingOptions options;
  options.max_per_class = 6;
  int pasted_total = 0;
  for (uint64_t seed = 0; seed < 25; ++seed) {
    const Det3dFrame& frame = frames[seed % frames.size()];
    const GtSamplingResult r = SampleGtObjects(frame, db, options, seed);
    // Same seed, same frame.
    const GtSamplingResult again = SampleGtObjects(frame, db, options, seed);
    EXPECT_EQ(again.frame.boxes, r.frame.boxes);
    ASSERT_EQ(again.frame.points.size(), r.frame.points.size());
    for (size_t i = 0; i < r.frame.points.size(); ++i) {
      EXPECT_EQ(again.frame.points[i].x, r.frame.points[i].x);
    }
    const int pasted = static_cast<int>(r.frame.boxes.size() - frame.boxes.size());
    EXPECT_EQ(pasted, r.pasted_per_class[0]);
    EXPECT_EQ(pasted + r.rejected, std::min<int>(6, db.objects_by_class[0].size()));
    pasted_total += pasted;
    // No two grown boxes overlap; the frame's own boxes keep every point they had; each pasted
    // box holds exactly its object's points.
    for (size_t a = 0; a < r.frame.boxes.size(); ++a) {
      for (size_t b = a + 1; b < r.frame.boxes.size(); ++b) {
        EXPECT_EQ(LidarBevIou(GrownBox(r.frame.boxes[a], 0.2), GrownBox(r.frame.boxes[b], 0.2)), 0);
      }
      auto count = [&](const Det3dFrame& f) {
        int n = 0;
        for (const VeloPoint& p : f.points) n += PointInBox(r.frame.boxes[a], p.x, p.y, p.z);
        return n;
      };
      if (a < frame.boxes.size()) {
        EXPECT_EQ(count(r.frame), count(frame));
      } else {
        int expected = -1;
        for (const GtObject& o : db.objects_by_class[0]) {
          if (o.box == r.frame.boxes[a]) {
            expected = 0;
            for (const VeloPoint& p : o.points) expected += PointInBox(o.box, p.x, p.y, p.z);
          }
        }
        EXPECT_EQ(count(r.frame), expected);
      }
    }
    // Removed points: exactly the frame's points inside a pasted grown box.
    int64_t covered = 0;
    for (const VeloPoint& p : frame.points) {
      bool in = false;
      for (size_t k = frame.boxes.size(); k < r.frame.boxes.size(); ++k) {
        in = in || PointInBox(GrownBox(r.frame.boxes[k], 0.2), p.x, p.y, p.z);
      }
      covered += in;
    }
    EXPECT_EQ(r.removed_points, covered);
  }
  EXPECT_GT(pasted_total, 25);  // it pastes, on average more than one object a frame
  GtSamplingOptions bad;
  bad.max_per_class = -1;
  EXPECT_THROW(SampleGtObjects(frames[0], db, bad, 1), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
