#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <utility>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/bipartite_internal.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/eval/voc_matcher_internal.h"

namespace stereodet {
namespace {

Object Box(const std::string& type, double left, double top, double right, double bottom,
           std::optional<double> score = std::nullopt, int occluded = 0) {
  Object o;
  o.type = type;
  o.box = Box2D{left, top, right, bottom};
  o.occluded = occluded;
  o.score = score;
  o.box3d.h = o.box3d.w = o.box3d.l = 1.0;
  o.box3d.location = Eigen::Vector3d(0, 1, 10);
  return o;
}

// A ClassFrame with the given overlaps (labels x detections, 0 = no edge), all valid, 100 px high.
ClassFrame HandFrame(const std::vector<std::vector<double>>& overlap,
                     const std::vector<double>& scores, double tau) {
  ClassFrame f;
  f.min_overlap = tau;
  const int nl = static_cast<int>(overlap.size());
  const int nd = static_cast<int>(scores.size());
  for (int i = 0; i < nl; ++i) {
    f.label_object.push_back(i);
    f.label_neighbour.push_back(0);
    f.label_difficulty.push_back(7);
    f.label_alpha.push_back(0);
  }
  for (int j = 0; j < nd; ++j) {
    f.det_object.push_back(j);
    f.det_is_class.push_back(1);
    f.det_height.push_back(100);
    f.det_score.push_back(scores[j]);
    f.det_alpha.push_back(0);
    f.det_dontcare.push_back(0);
  }
  f.edge_begin.push_back(0);
  for (int i = 0; i < nl; ++i) {
    for (int j = 0; j < nd; ++j) {
      if (overlap[i][j] >= tau) {
        f.edge_det.push_back(j);
        f.edge_overlap.push_back(overlap[i][j]);
      }
    }
    f.edge_begin.push_back(static_cast<int32_t>(f.edge_det.size()));
  }
  return f;
}

// The paper's Figure: two overlapping labels. KITTI's greedy (largest overlap, label order) and
// VOC's (score order, best label) find 1 TP, 1 FP, 1 FN; the optimal matcher 2 TP.
TEST(OptimalMatcherTest, PapersTwoOverlappingLabels) {
  EvalFrame f;
  f.labels.push_back(Box("Pedestrian", 0, 0, 100, 100));
  f.labels.push_back(Box("Pedestrian", 40, 0, 140, 100));
  f.detections.push_back(Box("Pedestrian", -30, 0, 80, 100, 0.8));  // IoU 0.615 with label 0 only
  f.detections.push_back(Box("Pedestrian", 20, 0, 120, 100, 0.9));  // IoU 0.667 with both
  const ClassFrame cf = PrepareClassFrame(f, KittiClassSpec("Pedestrian"), OverlapKind::k2D);
  for (const Matcher greedy : {Matcher::kKitti, Matcher::kVoc}) {
    const FrameAssociation a = Associate(greedy, cf, Difficulty::kModerate, 0.0);
    EXPECT_EQ(a.CountDets(Outcome::kTp), 1) << MatcherName(greedy);
    EXPECT_EQ(a.CountDets(Outcome::kFp), 1) << MatcherName(greedy);
    EXPECT_EQ(a.CountLabels(Outcome::kFn), 1) << MatcherName(greedy);
  }
  const FrameAssociation a = OptimalAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.CountDets(Outcome::kTp), 2);
  EXPECT_EQ(a.CountDets(Outcome::kFp), 0);
  EXPECT_EQ(a.CountLabels(Outcome::kFn), 0);
  EXPECT_EQ(a.label_det[0], 0);
  EXPECT_EQ(a.label_det[1], 1);
  std::vector<CurveEvent> events;
  events = OptimalFrameEvents(cf, Difficulty::kModerate, std::move(events));
  const std::vector<CurvePoint> curve = BuildCurve(events, 2);
  ASSERT_EQ(curve.size(), 2u);
  EXPECT_EQ(curve[0].tp, 1);  // at 0.9: one detection, one TP
  EXPECT_EQ(curve[1].tp, 2);
  EXPECT_EQ(curve[1].fp, 0);
  EXPECT_EQ(curve[1].fn, 0);
}

// tau = 0.5, three labels and three detections: the matching of largest plain IoU sum has 2 pairs
// (0.95 + 0.95), yet 3 pairs exist (0.55 * 3). The lexicographic weights find the 3.
TEST(OptimalMatcherTest, PlainIouSumPicksFewerTruePositives) {
  const std::vector<std::vector<double>> iou = {
      {0.95, 0.55, 0.0}, {0.0, 0.95, 0.55}, {0.55, 0.0, 0.0}};
  std::vector<WeightedEdge> plain;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (iou[i][j] >= 0.5) plain.push_back(WeightedEdge{i, j, LexWeight{0, iou[i][j]}});
    }
  }
  const std::vector<int32_t> by_iou = MaxWeightAssignment(3, 3, plain);
  EXPECT_EQ(std::count_if(by_iou.begin(), by_iou.end(), [](int j) { return j >= 0; }), 2);

  const ClassFrame cf = HandFrame(iou, {0.9, 0.8, 0.7}, 0.5);
  const FrameAssociation a = OptimalAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.CountDets(Outcome::kTp), 3);
  EXPECT_EQ(a.label_det[0], 1);
  EXPECT_EQ(a.label_det[1], 2);
  EXPECT_EQ(a.label_det[2], 0);
}

TEST(OptimalMatcherTest, AmongMaximumMatchingsTakesLargestOverlap) {
  // Both perfect matchings have 2 pairs; {0-0, 1-1} sums 1.5, {0-1, 1-0} sums 1.7.
  const ClassFrame cf = HandFrame({{0.8, 0.9}, {0.8, 0.7}}, {0.9, 0.8}, 0.5);
  const FrameAssociation a = OptimalAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.label_det[0], 1);
  EXPECT_EQ(a.label_det[1], 0);
}

// One label and detections overlapping only it (the matcher's one-pass path): the largest
// overlap wins, the lowest detection index among equal overlaps, and a detection inside DontCare
// only when no other is there (it could be excused; matching another covers one more
// unexcusable detection). The AOS curve (SingleLabelSimilarityEvents) relies on this choice.
TEST(OptimalMatcherTest, OneLabelTakesItsBestDetectionLowestIndexAmongEquals) {
  ClassFrame cf = HandFrame({{0.6, 0.8, 0.8, 0.9}, {0, 0, 0, 0}}, {0.9, 0.5, 0.7, 0.6}, 0.5);
  EXPECT_EQ(OptimalAssociate(cf, Difficulty::kModerate, 0.0).label_det[0], 3);
  EXPECT_EQ(OptimalAssociate(cf, Difficulty::kModerate, 0.65).label_det[0], 2);  // 3 below t
  cf.det_score = {0.9, 0.8, 0.8, 0.1};
  EXPECT_EQ(OptimalAssociate(cf, Difficulty::kModerate, 0.5).label_det[0], 1);  // 1 and 2 tie
  cf.det_dontcare = {0, 0, 0, 1};
  const FrameAssociation a = OptimalAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.label_det[0], 1);
  EXPECT_EQ(a.det_outcome[3], Outcome::kDontCare);
  EXPECT_EQ(a.label_det[1], -1);
  EXPECT_EQ(a.label_outcome[1], Outcome::kFn);
  cf.det_dontcare = {1, 1, 1, 1};
  EXPECT_EQ(OptimalAssociate(cf, Difficulty::kModerate, 0.0).label_det[0], 3);
}

// ------------------------------------------------------------------------------------------------
// Brute force: every association of a small frame.

struct Brute {
  int tp = -1, fp = 0, fn = 0;
  double iou = 0.0;
};

// Maximizes (TP, -FP, -FN, IoU) over all matchings of valid labels to valid detections above t.
Brute BruteForce(const ClassFrame& f, Difficulty d, double t) {
  const double min_h = KittiDifficultyLimits(d).min_height_px;
  const int nl = f.num_labels(), nd = f.num_dets();
  std::vector<int> valid_det, ignored_det;
  for (int j = 0; j < nd; ++j) {
    if (!f.det_is_class[j] || f.det_score[j] < t) continue;
    (std::trunc(f.det_height[j]) < min_h ? ignored_det : valid_det).push_back(j);
  }
  std::vector<std::vector<double>> ov(nl, std::vector<double>(nd, -1));
  for (int i = 0; i < nl; ++i) {
    for (int e = f.edge_begin[i]; e < f.edge_begin[i + 1]; ++e)
      ov[i][f.edge_det[e]] = f.edge_overlap[e];
  }
  std::vector<uint8_t> excusable(nd, 0), label_excused(nl, 0);
  for (int j : valid_det) {
    excusable[j] = f.det_dontcare[j];
    for (int i = 0; i < nl; ++i) excusable[j] |= !f.LabelValid(i, d) && ov[i][j] >= 0;
  }
  for (int j : ignored_det) {
    for (int i = 0; i < nl; ++i) label_excused[i] |= f.LabelValid(i, d) && ov[i][j] >= 0;
  }
  Brute best;
  std::vector<int> label_of(nd, -1);
  std::vector<int> det_of(nl, -1);
  std::function<void(int, int, double)> rec = [&](int i, int tp, double iou) {
    if (i == nl) {
      Brute b;
      b.tp = tp;
      b.iou = iou;
      for (int j : valid_det) b.fp += label_of[j] < 0 && !excusable[j];
      for (int k = 0; k < nl; ++k) b.fn += f.LabelValid(k, d) && det_of[k] < 0 && !label_excused[k];
      auto key = [](const Brute& x) { return std::make_tuple(x.tp, -x.fp, -x.fn); };
      if (key(b) > key(best) || (key(b) == key(best) && b.iou > best.iou)) best = b;
      return;
    }
    rec(i + 1, tp, iou);
    if (!f.LabelValid(i, d)) return;
    for (int j : valid_det) {
      if (label_of[j] >= 0 || ov[i][j] < 0) continue;
      label_of[j] = i;
      det_of[i] = j;
      rec(i + 1, tp + 1, iou + ov[i][j]);
      label_of[j] = -1;
      det_of[i] = -1;
    }
  };
  rec(0, 0, 0.0);
  return best;
}

EvalFrame RandomSmallFrame(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::uniform_int_distribution<int> count(0, 7);
  auto random_box = [&](const std::string& type, std::optional<double> score) {
    const double left = 200 * u(rng), top = 100 + 40 * u(rng);
    const double w = 30 + 60 * u(rng);
    const double h = u(rng) < 0.15 ? 15 + 15 * u(rng) : 30 + 60 * u(rng);  // some below 25 / 40 px
    return Box(type, left, top, left + w, top + h, score, u(rng) < 0.8 ? 0 : 2);
  };
  EvalFrame f;
  const int nl = count(rng), nd = count(rng);
  for (int i = 0; i < nl; ++i) {
    const double r = u(rng);
    f.labels.push_back(random_box(r < 0.75 ? "Car" : r < 0.9 ? "Van" : "DontCare", std::nullopt));
  }
  for (int j = 0; j < nd; ++j) {
    // Near a label most of the time, so that overlaps are common; scores with ties.
    Object det = random_box(u(rng) < 0.9 ? "Car" : "Pedestrian", std::round(10 * u(rng)) / 10);
    if (!f.labels.empty() && u(rng) < 0.8) {
      const Object& l = f.labels[std::uniform_int_distribution<int>(0, nl - 1)(rng)];
      const double dx = 20 * (u(rng) - 0.5), dy = 20 * (u(rng) - 0.5);
      det.box = Box2D{l.box.left + dx, l.box.top + dy, l.box.right + dx * u(rng),
                      l.box.bottom + dy * u(rng)};
    }
    f.detections.push_back(det);
  }
  return f;
}

TEST(OptimalMatcherTest, EqualsBruteForceAtEveryThresholdOnThousandsOfFrames) {
  std::mt19937_64 rng(7);
  ClassSpec spec = KittiClassSpec("Car");
  spec.min_overlap = {0.4, 0.4, 0.4};
  int checked = 0, optimal_beats_greedy = 0;
  for (int trial = 0; trial < 2500; ++trial) {
    const EvalFrame frame = RandomSmallFrame(rng);
    const ClassFrame cf = PrepareClassFrame(frame, spec, OverlapKind::k2D);
    for (const Difficulty d : {Difficulty::kEasy, Difficulty::kHard}) {
      std::vector<CurveEvent> events;
      events = OptimalFrameEvents(cf, d, std::move(events));
      const int n_valid = CountValidLabels(cf, d);
      const std::vector<CurvePoint> curve = BuildCurve(events, n_valid);
      // Every distinct score is a threshold to check (and one above all scores).
      std::vector<double> thresholds = cf.det_score;
      thresholds.push_back(2.0);
      for (const double t : thresholds) {
        const Brute b = BruteForce(cf, d, t);
        // The curve's counts at t: the last point with threshold >= t.
        CurvePoint at;
        at.fn = n_valid;
        for (const CurvePoint& p : curve) {
          if (p.threshold >= t) at = p;
        }
        ASSERT_EQ(at.tp, b.tp) << "trial " << trial << " t " << t;
        ASSERT_EQ(at.fp, b.fp) << "trial " << trial << " t " << t;
        ASSERT_EQ(at.fn, b.fn) << "trial " << trial << " t " << t;
        const FrameAssociation a = OptimalAssociate(cf, d, t);
        ASSERT_EQ(a.CountDets(Outcome::kTp), b.tp);
        ASSERT_EQ(a.CountDets(Outcome::kFp), b.fp);
        ASSERT_EQ(a.CountLabels(Outcome::kFn), b.fn);
        double iou = 0;
        for (int i = 0; i < cf.num_labels(); ++i) {
          if (a.label_det[i] < 0) continue;
          for (int e = cf.edge_begin[i]; e < cf.edge_begin[i + 1]; ++e) {
            if (cf.edge_det[e] == a.label_det[i]) iou += cf.edge_overlap[e];
          }
        }
        ASSERT_NEAR(iou, b.iou, 1e-9) << "trial " << trial;
        // Never fewer TPs than the greedy matchers.
        const int64_t kitti_tp = KittiAssociate(cf, d, t).CountDets(Outcome::kTp);
        const int64_t voc_tp = VocAssociate(cf, d, t).CountDets(Outcome::kTp);
        ASSERT_GE(b.tp, kitti_tp);
        ASSERT_GE(b.tp, voc_tp);
        optimal_beats_greedy += b.tp > kitti_tp;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 10000);
  EXPECT_GT(optimal_beats_greedy, 0);  // the random frames do contain greedy's mistakes
}

// The combined calls Evaluate makes (OptimalAssociator: one graph for the curve and the operating
// point) give exactly the events and the association of the two separate calls, also when the
// association's memory comes from another frame and when the events are appended to earlier ones.
TEST(OptimalMatcherTest, EventsAndAssociateTogetherEqualTheSeparateCalls) {
  std::mt19937_64 rng(11);
  ClassSpec spec = KittiClassSpec("Car");
  spec.min_overlap = {0.4, 0.4, 0.4};
  FrameAssociation reuse;
  int with_tp = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    const ClassFrame cf = PrepareClassFrame(RandomSmallFrame(rng), spec, OverlapKind::k2D);
    for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
      const double t = trial % 3 == 0 ? -std::numeric_limits<double>::infinity() : 0.5;
      std::vector<CurveEvent> separate(1), together(1);  // one earlier event, kept first
      separate[0].score = together[0].score = 9.0;
      separate = OptimalFrameEvents(cf, d, std::move(separate));
      const FrameAssociation expected = OptimalAssociate(cf, d, t);
      const OptimalAssociator associator(cf, d);
      associator.AppendFrameEvents(&together);
      reuse = associator.At(t, std::move(reuse));
      ASSERT_EQ(together.size(), separate.size()) << "trial " << trial;
      for (size_t k = 0; k < separate.size(); ++k) {
        ASSERT_EQ(together[k].score, separate[k].score) << "trial " << trial;
        ASSERT_EQ(together[k].tp, separate[k].tp) << "trial " << trial;
        ASSERT_EQ(together[k].fp, separate[k].fp) << "trial " << trial;
        ASSERT_EQ(together[k].fn, separate[k].fn) << "trial " << trial;
      }
      ASSERT_EQ(reuse.label_outcome, expected.label_outcome) << "trial " << trial;
      ASSERT_EQ(reuse.label_det, expected.label_det) << "trial " << trial;
      ASSERT_EQ(reuse.det_outcome, expected.det_outcome) << "trial " << trial;
      ASSERT_EQ(reuse.det_label, expected.det_label) << "trial " << trial;
      with_tp += expected.CountDets(Outcome::kTp) > 0;
    }
  }
  EXPECT_GT(with_tp, 1000);  // the frames do have pairs to get right
}

}  // namespace
}  // namespace stereodet
