#include "stereodet/eval/curves.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <utility>
#include <vector>

namespace stereodet {
namespace {

// The interpolated AP as defined (curves.h), by sorting the points by recall: the reference for
// the linear-time implementation.
double ReferenceInterpolatedAp(const std::vector<CurvePoint>& curve, int first, int last,
                               double step, bool orientation) {
  std::vector<std::pair<double, double>> pr;
  for (const CurvePoint& p : curve) {
    if (p.tp + p.fp > 0) pr.emplace_back(p.recall, orientation ? p.orientation : p.precision);
  }
  std::sort(pr.begin(), pr.end());
  for (size_t i = pr.size(); i-- > 1;) pr[i - 1].second = std::max(pr[i - 1].second, pr[i].second);
  double sum = 0.0;
  for (int k = first; k <= last; ++k) {
    const double r = k * step;
    const auto it =
        std::lower_bound(pr.begin(), pr.end(), r,
                         [](const std::pair<double, double>& a, double v) { return a.first < v; });
    if (it != pr.end()) sum += it->second;
  }
  return sum / (last - first + 1) * 100.0;
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// Random curves with recall ties, recall exactly on the levels (k / 40, k / 10), points without a
// detection, in and out of recall order: every summary bit for bit the reference's.
TEST(CurvesTest, InterpolatedApEqualsItsDefinitionOnRandomCurves) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int n = 0; n < 3000; ++n) {
    const int num_points = static_cast<int>(rng() % 60);
    std::vector<CurvePoint> curve;
    for (int i = 0; i < num_points; ++i) {
      CurvePoint p;
      p.tp = static_cast<int64_t>(rng() % 20);
      p.fp = rng() % 5 == 0 ? 0 : static_cast<int64_t>(rng() % 20);
      const int pick = static_cast<int>(rng() % 3);
      p.recall = pick == 0   ? static_cast<double>(rng() % 41) / 40.0
                 : pick == 1 ? static_cast<double>(rng() % 11) / 10.0
                             : u(rng);
      p.precision = rng() % 4 == 0 ? 1.0 : u(rng);
      p.orientation = p.precision * u(rng);
      curve.push_back(p);
    }
    if (n % 2 == 0) {  // in recall order, as most curves are
      std::sort(curve.begin(), curve.end(),
                [](const CurvePoint& a, const CurvePoint& b) { return a.recall < b.recall; });
    }
    SCOPED_TRACE(n);
    ASSERT_TRUE(SameBits(InterpolatedApR40(curve),
                         ReferenceInterpolatedAp(curve, 1, 40, 1.0 / 40.0, false)));
    ASSERT_TRUE(SameBits(InterpolatedApR11(curve),
                         ReferenceInterpolatedAp(curve, 0, 10, 1.0 / 10.0, false)));
    ASSERT_TRUE(SameBits(InterpolatedAosR40(curve),
                         ReferenceInterpolatedAp(curve, 1, 40, 1.0 / 40.0, true)));
    ASSERT_TRUE(SameBits(InterpolatedAosR11(curve),
                         ReferenceInterpolatedAp(curve, 0, 10, 1.0 / 10.0, true)));
  }
}

TEST(CurvesTest, InterpolatedApOfAPerfectCurveIs100) {
  // 40 labels, found one by one with precision 1: R40 = 100 (no devkit slot quirk here).
  std::vector<CurveEvent> events;
  for (int i = 0; i < 40; ++i) events.push_back(CurveEvent{1.0 - i / 100.0, 1, 0, -1});
  const std::vector<CurvePoint> curve = BuildCurve(events, 40);
  EXPECT_DOUBLE_EQ(InterpolatedApR40(curve), 100.0);
  EXPECT_DOUBLE_EQ(InterpolatedApR11(curve), 100.0);
  EXPECT_DOUBLE_EQ(EveryPointAp(curve), 100.0);
  EXPECT_DOUBLE_EQ(BestF1(curve).f1, 1.0);
}

TEST(CurvesTest, EveryPointApIntegratesTheEnvelope) {
  // Labels: 2. Scores: TP, FP, TP -> (P, R) = (1, .5), (.5, .5), (2/3, 1).
  const std::vector<CurvePoint> curve =
      BuildCurve({{0.9, 1, 0, -1}, {0.8, 0, 1, 0}, {0.7, 1, 0, -1}}, 2);
  ASSERT_EQ(curve.size(), 3u);
  EXPECT_NEAR(EveryPointAp(curve), (0.5 * 1.0 + 0.5 * 2.0 / 3.0) * 100, 1e-12);
  // R11: r = 0..0.5 -> 1 (6 levels), r = 0.6..1 -> 2/3 (5 levels).
  EXPECT_NEAR(InterpolatedApR11(curve), (6 * 1.0 + 5 * 2.0 / 3.0) / 11 * 100, 1e-12);
}

// Events of one score are summed in their order in the list (the sort is stable), so the
// similarity's floating-point sum is the list's, whatever the sort: 1e16 + 1 rounds back to 1e16.
TEST(CurvesTest, BuildCurveSumsEqualScoresInTheEventsOrder) {
  auto event = [](double score, double similarity) {
    CurveEvent e;
    e.score = score;
    e.tp = 1;
    e.similarity = similarity;
    return e;
  };
  const std::vector<CurvePoint> lost =
      BuildCurve({event(0.5, 1e16), event(0.5, 1.0), event(0.5, -1e16), event(0.9, 0.0)}, 4);
  const std::vector<CurvePoint> kept =
      BuildCurve({event(0.5, 1e16), event(0.5, -1e16), event(0.5, 1.0), event(0.9, 0.0)}, 4);
  ASSERT_EQ(lost.size(), 2u);
  ASSERT_EQ(kept.size(), 2u);
  EXPECT_EQ(lost[0].threshold, 0.9);
  EXPECT_EQ(lost[1].threshold, 0.5);
  EXPECT_EQ(lost[1].tp, 4);
  EXPECT_EQ(lost[1].similarity, 0.0);
  EXPECT_EQ(kept[1].similarity, 1.0);
}

// Property: BuildCurve's points are bit for bit those of a stable sort of the events by
// descending score followed by the running sums, on random events with few distinct scores (many
// ties, each event with its own similarity, so the order inside a tie shows), negative scores and
// both zeros, from a handful of events to more than the radix sort's threshold.
TEST(CurvesTest, BuildCurveEqualsAStableSortOfTheEvents) {
  std::mt19937_64 rng(5);
  for (const size_t n : {0, 1, 5, 63, 64, 300, 5000}) {
    for (const int distinct : {1, 7, 100, 1000000}) {
      std::uniform_int_distribution<int> score(0, distinct - 1), count(-1, 1);
      std::uniform_real_distribution<double> similarity(-1.0, 1.0);
      std::vector<CurveEvent> events(n);
      for (CurveEvent& e : events) {
        const int k = score(rng);
        e.score = k == 0 ? (count(rng) < 0 ? -0.0 : 0.0) : (k - distinct / 2) / 100.0;
        e.tp = count(rng);
        e.fp = count(rng);
        e.fn = count(rng);
        e.similarity = similarity(rng);
      }
      std::vector<CurveEvent> sorted = events;
      std::stable_sort(sorted.begin(), sorted.end(),
                       [](const CurveEvent& a, const CurveEvent& b) { return a.score > b.score; });
      std::vector<CurvePoint> want;
      CurvePoint current;
      current.fn = 40;
      for (size_t i = 0; i < sorted.size();) {
        const double s = sorted[i].score;
        for (; i < sorted.size() && sorted[i].score == s; ++i) {
          current.tp += sorted[i].tp;
          current.fp += sorted[i].fp;
          current.fn += sorted[i].fn;
          current.similarity += sorted[i].similarity;
        }
        current.threshold = s;
        current = FinishPoint(current);
        want.push_back(current);
      }
      const std::vector<CurvePoint> got = BuildCurve(events, 40);
      ASSERT_EQ(got.size(), want.size()) << n << " " << distinct;
      for (size_t k = 0; k < got.size(); ++k) {
        ASSERT_EQ(got[k].threshold, want[k].threshold) << n << " " << distinct << " " << k;
        EXPECT_EQ(got[k].tp, want[k].tp);
        EXPECT_EQ(got[k].fp, want[k].fp);
        EXPECT_EQ(got[k].fn, want[k].fn);
        EXPECT_TRUE(SameBits(got[k].similarity, want[k].similarity)) << n << " " << k;
        EXPECT_TRUE(SameBits(got[k].orientation, want[k].orientation)) << n << " " << k;
      }
    }
  }
}

}  // namespace
}  // namespace stereodet
