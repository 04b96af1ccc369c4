#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "stereodet/eval/curve_events_internal.h"
#include "stereodet/eval/devkit_overlap_internal.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/kitti_matcher_internal.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/selection_mask_internal.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

// ------------------------------------------------------------------------------------------------
// A literal re-statement of the devkit's control flow (cleanData / computeStatistics / eval_class),
// dense and slow, over raw Objects: the reference the optimized matcher must equal exactly.
// Overlaps are the ones KITTI mode decides with (RefOverlaps; their devkit arithmetic is tested in
// devkit_overlap_test.cc and frame_data_test.cc): this reference is about the control flow.

struct RefStats {
  int64_t tp = 0, fp = 0, fn = 0;
  double similarity = 0.0;
  std::vector<double> v;
};

struct RefClean {
  std::vector<int> ignored_gt, ignored_det;
  std::vector<const Object*> dc;
  int n_gt = 0;
  std::vector<std::vector<double>> overlap;  // [label][detection], RefOverlaps
};

// KITTI mode's overlaps, restated densely: KittiOverlapAtThreshold for each pair; in BEV and 3D, a
// label's overlaps >= tau with detections that take part (the class, or lower than 40 px) that lie
// within kDevkitTieBand of another such overlap of the label are the devkit's.
std::vector<std::vector<double>> RefOverlaps(const EvalFrame& frame, const ClassSpec& spec,
                                             OverlapKind kind, double tau) {
  const auto& gt = frame.labels;
  const auto& det = frame.detections;
  std::vector<std::vector<double>> ov(gt.size(), std::vector<double>(det.size()));
  for (size_t i = 0; i < gt.size(); ++i) {
    for (size_t j = 0; j < det.size(); ++j) {
      ov[i][j] = KittiOverlapAtThreshold(kind, det[j], gt[i], tau);
    }
  }
  if (kind == OverlapKind::k2D) return ov;
  auto candidate = [&](size_t i, size_t j) {
    return ov[i][j] >= tau && (EqualsIgnoreCase(det[j].type, spec.name) ||
                               std::fabs(det[j].box.top - det[j].box.bottom) < 40);
  };
  for (size_t i = 0; i < gt.size(); ++i) {
    std::vector<double> row = ov[i];
    for (size_t j = 0; j < det.size(); ++j) {
      for (size_t k = 0; k < det.size() && candidate(i, j); ++k) {
        if (k == j || !candidate(i, k) || std::fabs(ov[i][j] - ov[i][k]) > kDevkitTieBand) continue;
        row[j] = DevkitBoxOverlap(kind, DevkitCriterion::kUnion, det[j].box3d, gt[i].box3d)
                     .value_or(ov[i][j]);
        break;
      }
    }
    ov[i] = row;
  }
  return ov;
}

RefClean RefCleanData(const EvalFrame& frame, const ClassSpec& spec, Difficulty difficulty) {
  RefClean c;
  const DifficultyLimits lim = KittiDifficultyLimits(difficulty);
  for (const Object& g : frame.labels) {
    int valid_class = -1;
    if (EqualsIgnoreCase(g.type, spec.name)) valid_class = 1;
    for (const std::string& n : spec.neighbours) {
      if (valid_class != 1 && EqualsIgnoreCase(g.type, n)) valid_class = 0;
    }
    const double height = g.box.bottom - g.box.top;
    const bool ignore = g.occluded > lim.max_occlusion || g.truncated > lim.max_truncation ||
                        height <= lim.min_height_px;
    if (valid_class == 1 && !ignore) {
      c.ignored_gt.push_back(0);
      ++c.n_gt;
    } else if (valid_class == 0 || (ignore && valid_class == 1)) {
      c.ignored_gt.push_back(1);
    } else {
      c.ignored_gt.push_back(-1);
    }
  }
  for (const Object& g : frame.labels) {
    if (EqualsIgnoreCase(g.type, "DontCare")) c.dc.push_back(&g);
  }
  for (const Object& d : frame.detections) {
    const int valid_class = EqualsIgnoreCase(d.type, spec.name) ? 1 : -1;
    const int height = static_cast<int>(std::fabs(d.box.top - d.box.bottom));
    if (height < lim.min_height_px)
      c.ignored_det.push_back(1);
    else if (valid_class == 1)
      c.ignored_det.push_back(0);
    else
      c.ignored_det.push_back(-1);
  }
  return c;
}

RefStats RefComputeStatistics(const EvalFrame& frame, const RefClean& c, OverlapKind kind,
                              double tau, bool compute_fp, double thresh) {
  RefStats stat;
  const double kNoDetection = -10000000;
  const auto& gt = frame.labels;
  const auto& det = frame.detections;
  std::vector<bool> assigned(det.size(), false), ignored_threshold(det.size(), false);
  if (compute_fp) {
    for (size_t i = 0; i < det.size(); ++i) ignored_threshold[i] = *det[i].score < thresh;
  }
  for (size_t i = 0; i < gt.size(); ++i) {
    if (c.ignored_gt[i] == -1) continue;
    int det_idx = -1;
    double valid_detection = kNoDetection, max_overlap = 0;
    bool assigned_ignored_det = false;
    for (size_t j = 0; j < det.size(); ++j) {
      if (c.ignored_det[j] == -1 || assigned[j] || ignored_threshold[j]) continue;
      const double overlap = c.overlap[i][j];
      if (!compute_fp && overlap > tau && *det[j].score > valid_detection) {
        det_idx = static_cast<int>(j);
        valid_detection = *det[j].score;
      } else if (compute_fp && overlap > tau && (overlap > max_overlap || assigned_ignored_det) &&
                 c.ignored_det[j] == 0) {
        max_overlap = overlap;
        det_idx = static_cast<int>(j);
        valid_detection = 1;
        assigned_ignored_det = false;
      } else if (compute_fp && overlap > tau && valid_detection == kNoDetection &&
                 c.ignored_det[j] == 1) {
        det_idx = static_cast<int>(j);
        valid_detection = 1;
        assigned_ignored_det = true;
      }
    }
    if (valid_detection == kNoDetection && c.ignored_gt[i] == 0) {
      ++stat.fn;
    } else if (valid_detection != kNoDetection &&
               (c.ignored_gt[i] == 1 || c.ignored_det[det_idx] == 1)) {
      assigned[det_idx] = true;
    } else if (valid_detection != kNoDetection) {
      ++stat.tp;
      stat.v.push_back(*det[det_idx].score);
      stat.similarity += (1.0 + std::cos(gt[i].alpha - det[det_idx].alpha)) / 2.0;
      assigned[det_idx] = true;
    }
  }
  if (compute_fp) {
    for (size_t i = 0; i < det.size(); ++i) {
      if (!(assigned[i] || c.ignored_det[i] == -1 || c.ignored_det[i] == 1 || ignored_threshold[i]))
        ++stat.fp;
    }
    int nstuff = 0;
    for (const Object* dc : c.dc) {
      for (size_t j = 0; j < det.size(); ++j) {
        if (assigned[j] || c.ignored_det[j] == -1 || c.ignored_det[j] == 1 || ignored_threshold[j])
          continue;
        if (KittiDontCareOverlapAtThreshold(kind, det[j], *dc, tau) > tau) {
          assigned[j] = true;
          ++nstuff;
        }
      }
    }
    stat.fp -= nstuff;
  }
  return stat;
}

KittiClassResult RefEvalClass(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                              OverlapKind kind, Difficulty difficulty) {
  const double tau = spec.min_overlap[static_cast<int>(kind)];
  KittiClassResult r;
  std::vector<double> v;
  std::vector<RefClean> cleans;
  for (const EvalFrame& f : frames) {
    cleans.push_back(RefCleanData(f, spec, difficulty));
    cleans.back().overlap = RefOverlaps(f, spec, kind, tau);
    r.num_groundtruth += cleans.back().n_gt;
    const RefStats s = RefComputeStatistics(f, cleans.back(), kind, tau, false, 0);
    v.insert(v.end(), s.v.begin(), s.v.end());
  }
  r.thresholds = KittiThresholds(v, static_cast<double>(r.num_groundtruth));
  r.counts.assign(r.thresholds.size(), KittiCounts{});
  for (size_t i = 0; i < frames.size(); ++i) {
    for (size_t t = 0; t < r.thresholds.size(); ++t) {
      const RefStats s =
          RefComputeStatistics(frames[i], cleans[i], kind, tau, true, r.thresholds[t]);
      r.counts[t].tp += s.tp;
      r.counts[t].fp += s.fp;
      r.counts[t].fn += s.fn;
      r.counts[t].similarity += s.similarity;
    }
  }
  std::array<double, kKittiSamplePoints> precision{}, aos{};
  for (size_t i = 0; i < r.thresholds.size(); ++i) {
    precision[i] = r.counts[i].tp / static_cast<double>(r.counts[i].tp + r.counts[i].fp);
    aos[i] = r.counts[i].similarity / static_cast<double>(r.counts[i].tp + r.counts[i].fp);
  }
  for (size_t i = 0; i < r.thresholds.size(); ++i) {
    precision[i] = *std::max_element(precision.begin() + i, precision.end());
    aos[i] = *std::max_element(aos.begin() + i, aos.end());
  }
  r.precision = precision;
  r.aos = aos;
  r.ap_r11 = KittiApR11(precision);
  r.ap_r40 = KittiApR40(precision);
  r.aos_r40 = KittiApR40(aos);
  return r;
}

KittiClassResult RunKitti(const std::vector<EvalFrame>& frames, const ClassSpec& spec,
                          OverlapKind kind, Difficulty difficulty) {
  std::vector<ClassFrame> cfs;
  for (const EvalFrame& f : frames) cfs.push_back(PrepareClassFrame(f, spec, kind));
  return EvaluateKittiClass(cfs, difficulty, 2);
}

using testing_objects::Det;
using testing_objects::Label;

// ------------------------------------------------------------------------------------------------

TEST(KittiMatcherTest, ThresholdsOfAPerfectDetectorOn40LabelsKeepEveryScore) {
  std::vector<double> scores(40);
  std::iota(scores.begin(), scores.end(), 1.0);
  const std::vector<double> t = KittiThresholds(scores, 40);
  ASSERT_EQ(t.size(), 40u);
  EXPECT_EQ(t.front(), 40.0);
  EXPECT_EQ(t.back(), 1.0);
}

TEST(KittiMatcherTest, ThresholdsSubsampleToRecallStepsAndKeepTheLast) {
  // 400 labels, 400 TPs: one score every 10 (recall steps of 1/40), plus the last.
  std::vector<double> scores(400);
  std::iota(scores.begin(), scores.end(), 0.0);
  const std::vector<double> t = KittiThresholds(scores, 400);
  ASSERT_LE(t.size(), 41u);
  EXPECT_EQ(t.front(), 399.0);  // the first TP score is always kept
  EXPECT_EQ(t.back(), 0.0);     // and the last
  EXPECT_TRUE(std::is_sorted(t.rbegin(), t.rend()));
}

TEST(KittiMatcherTest, ThresholdsEmptyWhenNoTruePositive) {
  EXPECT_TRUE(KittiThresholds({}, 10).empty());
}

// The quirk in the issue: a perfect detector on 40 labels gets AP_R40 = 97.5, since threshold i
// sits in slot i (recall (i+1)/40) and slot 40 stays 0.
TEST(KittiMatcherTest, PerfectDetectorOn40LabelsScores97Point5) {
  std::vector<EvalFrame> frames(40);
  for (int i = 0; i < 40; ++i) {
    const Box2D box{100, 100, 200, 200};
    frames[i].labels.push_back(Label("Car", box));
    frames[i].detections.push_back(Det("Car", box, 0.5 + i / 100.0));
  }
  const KittiClassResult r =
      RunKitti(frames, KittiClassSpec("Car"), OverlapKind::k2D, Difficulty::kModerate);
  EXPECT_EQ(r.num_groundtruth, 40);
  EXPECT_EQ(r.thresholds.size(), 40u);
  EXPECT_DOUBLE_EQ(r.ap_r40, 97.5);
  EXPECT_DOUBLE_EQ(r.ap_r11, 10.0 / 11.0 * 100.0);
  EXPECT_DOUBLE_EQ(r.precision[39], 1.0);
  EXPECT_DOUBLE_EQ(r.precision[40], 0.0);
}

TEST(KittiMatcherTest, NeighbourClassAndDontCareAreNotFalsePositives) {
  EvalFrame f;
  f.labels.push_back(Label("Car", {100, 100, 200, 200}));
  f.labels.push_back(Label("Van", {300, 100, 400, 200}));
  f.labels.push_back(Label("DontCare", {500, 100, 600, 200}));
  f.detections.push_back(Det("Car", {100, 100, 200, 200}, 0.9));  // TP
  f.detections.push_back(Det("Car", {300, 100, 400, 200}, 0.8));  // on the Van: ignored
  f.detections.push_back(Det("Car", {510, 110, 590, 190}, 0.7));  // inside DontCare: ignored
  f.detections.push_back(Det("Car", {700, 100, 800, 200}, 0.6));  // FP
  const KittiClassResult r =
      RunKitti({f}, KittiClassSpec("Car"), OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_EQ(r.thresholds.size(), 1u);
  EXPECT_EQ(r.counts[0].tp, 1);
  EXPECT_EQ(r.counts[0].fp, 0);  // threshold 0.9: only the TP is above it
  ClassFrame cf = PrepareClassFrame(f, KittiClassSpec("Car"), OverlapKind::k2D);
  const FrameAssociation a = KittiAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.CountDets(Outcome::kTp), 1);
  EXPECT_EQ(a.CountDets(Outcome::kFp), 1);
  EXPECT_EQ(a.CountDets(Outcome::kIgnored), 1);   // on the Van
  EXPECT_EQ(a.CountDets(Outcome::kDontCare), 1);  // inside DontCare
  EXPECT_EQ(a.det_outcome[2], Outcome::kDontCare);
}

// Quirk: a detection lower than the minimum height is "ignored" whatever its class, and such a
// detection may take a label: a 30 px Pedestrian detection on a Car label at Easy (min 40 px) makes
// the car neither TP nor FN.
TEST(KittiMatcherTest, LowDetectionOfAnotherClassAbsorbsALabel) {
  EvalFrame f;
  f.labels.push_back(Label("Car", {100, 100, 200, 150}));                // 50 px: Easy
  f.detections.push_back(Det("Pedestrian", {100, 100, 200, 139}, 0.9));  // 39 px, IoU 0.78
  f.detections.push_back(Det("Car", {600, 100, 700, 200}, 0.5));         // unrelated FP
  ClassFrame cf = PrepareClassFrame(f, KittiClassSpec("Car"), OverlapKind::k2D);
  FrameAssociation a = KittiAssociate(cf, Difficulty::kEasy, 0.0);
  EXPECT_EQ(a.CountLabels(Outcome::kFn), 0);
  EXPECT_EQ(a.CountLabels(Outcome::kTp), 0);
  // At Moderate (min 25 px) the 39 px Pedestrian is simply another class: the car is a FN.
  a = KittiAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.CountLabels(Outcome::kFn), 1);
}

// Pass 1 takes the highest score, pass 2 the largest overlap.
TEST(KittiMatcherTest, ThresholdPassTakesHighestScorePrPassTakesLargestOverlap) {
  EvalFrame f;
  f.labels.push_back(Label("Car", {100, 100, 200, 200}));
  f.detections.push_back(Det("Car", {100, 100, 200, 190}, 0.6));  // IoU 0.9
  f.detections.push_back(Det("Car", {100, 100, 200, 175}, 0.9));  // IoU 0.75
  std::vector<double> scores;
  ClassFrame cf = PrepareClassFrame(f, KittiClassSpec("Car"), OverlapKind::k2D);
  scores = KittiCollectTpScores(cf, Difficulty::kModerate, std::move(scores)).scores;
  ASSERT_EQ(scores.size(), 1u);
  EXPECT_EQ(scores[0], 0.9);
  const FrameAssociation a = KittiAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.label_det[0], 0);  // the 0.6 detection, of larger overlap
  EXPECT_EQ(a.det_outcome[1], Outcome::kFp);
}

// Overlap must exceed the threshold strictly.
TEST(KittiMatcherTest, OverlapEqualToThresholdIsNoMatch) {
  EvalFrame f;
  f.labels.push_back(Label("Pedestrian", {0, 0, 100, 100}));
  f.detections.push_back(Det("Pedestrian", {0, 0, 100, 50}, 0.9));  // IoU exactly 0.5
  ClassFrame cf = PrepareClassFrame(f, KittiClassSpec("Pedestrian"), OverlapKind::k2D);
  const FrameAssociation a = KittiAssociate(cf, Difficulty::kModerate, 0.0);
  EXPECT_EQ(a.CountLabels(Outcome::kFn), 1);
}

class KittiMatcherBySeedTest : public ::testing::TestWithParam<int> {};

TEST_P(KittiMatcherBySeedTest, MatchesTheReferenceOnRandomFrames) {
  RandomFramesOptions ro;
  ro.num_frames = 40;
  ro.seed = 100 + GetParam();
  ro.crowded = GetParam() % 2 == 1;
  ro.score_decimals = GetParam() % 3 == 0 ? 2 : 0;  // ties
  ro.labels_per_frame = ro.crowded ? 8 : 5;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (const char* name : {"Car", "Pedestrian", "Cyclist"}) {
    for (const bool loose : {false, true}) {
      const ClassSpec spec = KittiClassSpec(name, loose);
      for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D}) {
        for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
          SCOPED_TRACE(std::string(name) + " " + OverlapKindName(kind) + " " + DifficultyName(d) +
                       (loose ? " loose" : ""));
          const KittiClassResult ref = RefEvalClass(frames, spec, kind, d);
          const KittiClassResult got = RunKitti(frames, spec, kind, d);
          EXPECT_EQ(got.num_groundtruth, ref.num_groundtruth);
          ASSERT_EQ(got.thresholds, ref.thresholds);
          for (size_t t = 0; t < ref.thresholds.size(); ++t) {
            EXPECT_EQ(got.counts[t].tp, ref.counts[t].tp) << t;
            EXPECT_EQ(got.counts[t].fp, ref.counts[t].fp) << t;
            EXPECT_EQ(got.counts[t].fn, ref.counts[t].fn) << t;
            EXPECT_NEAR(got.counts[t].similarity, ref.counts[t].similarity, 1e-9) << t;
          }
          EXPECT_NEAR(got.ap_r40, ref.ap_r40, 1e-9);
          EXPECT_NEAR(got.ap_r11, ref.ap_r11, 1e-9);
          EXPECT_NEAR(got.aos_r40, ref.aos_r40, 1e-9);
        }
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, KittiMatcherBySeedTest, ::testing::Range(0, 6));

// KittiPasses, driven as Evaluate drives it (all difficulties of a frame at once) but with its
// blocks in reverse order, gives each difficulty exactly EvaluateKittiClass's result, bit for bit.
TEST(KittiMatcherTest, PassesOverAllDifficultiesInAnyBlockOrderEqualOneAtATime) {
  RandomFramesOptions ro;
  ro.num_frames = 300;  // five blocks
  ro.seed = 21;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  const std::vector<Difficulty> all = {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard};
  for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kBev}) {
    std::vector<ClassFrame> cfs;
    for (const EvalFrame& f : frames)
      cfs.push_back(PrepareClassFrame(f, KittiClassSpec("Car"), kind));
    KittiPasses passes(cfs.size(), all);
    const size_t num_blocks = (cfs.size() + KittiPasses::kBlock - 1) / KittiPasses::kBlock;
    auto reverse_blocks = [&](auto fn) {
      for (size_t b = num_blocks; b-- > 0;) {
        for (size_t i = b * KittiPasses::kBlock;
             i < std::min(cfs.size(), (b + 1) * KittiPasses::kBlock); ++i) {
          fn(i);
        }
      }
    };
    reverse_blocks([&](size_t i) { passes.CollectFrame(i, cfs[i]); });
    passes.ChooseThresholds();
    reverse_blocks([&](size_t i) { passes.CountFrame(i, cfs[i]); });
    const std::vector<KittiClassResult> got = passes.Finish();
    ASSERT_EQ(got.size(), all.size());
    for (size_t d = 0; d < all.size(); ++d) {
      const KittiClassResult want = EvaluateKittiClass(cfs, all[d], 1);
      EXPECT_EQ(got[d].num_groundtruth, want.num_groundtruth);
      ASSERT_EQ(got[d].thresholds, want.thresholds);
      ASSERT_FALSE(want.thresholds.empty());
      for (size_t t = 0; t < want.thresholds.size(); ++t) {
        EXPECT_EQ(got[d].counts[t].tp, want.counts[t].tp);
        EXPECT_EQ(got[d].counts[t].fp, want.counts[t].fp);
        EXPECT_EQ(got[d].counts[t].fn, want.counts[t].fn);
        EXPECT_EQ(got[d].counts[t].similarity, want.counts[t].similarity);  // same order of sums
      }
      EXPECT_EQ(got[d].ap_r40, want.ap_r40);
      EXPECT_EQ(got[d].aos_r40, want.aos_r40);
    }
  }
}

// ClassFrameBuilder derives each detection's state per difficulty (ClassFrame::det_state); a
// ClassFrame put together without it (as by hand, or curve_events' components) is evaluated the
// same, the KITTI matcher deriving the states itself: every pass, bit for bit.
TEST(KittiMatcherTest, FramesWithoutDerivedStatesGiveTheSameResults) {
  RandomFramesOptions ro;
  ro.num_frames = 120;
  ro.seed = 5;
  ro.crowded = true;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::k3D}) {
    std::vector<ClassFrame> with, without;
    for (const EvalFrame& f : frames) {
      with.push_back(PrepareClassFrame(f, KittiClassSpec("Pedestrian"), kind));
      ASSERT_EQ(with.back().det_state.size(), with.back().det_object.size() * kNumDifficulties);
      without.push_back(with.back());
      without.back().det_state.clear();
    }
    for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
      SCOPED_TRACE(std::string(OverlapKindName(kind)) + " " + DifficultyName(d));
      const KittiClassResult a = EvaluateKittiClass(with, d, 1);
      const KittiClassResult b = EvaluateKittiClass(without, d, 1);
      ASSERT_FALSE(a.thresholds.empty());
      EXPECT_EQ(a.thresholds, b.thresholds);
      EXPECT_EQ(a.precision, b.precision);
      EXPECT_EQ(a.aos, b.aos);
      for (size_t i = 0; i < with.size(); ++i) {
        const FrameAssociation x = KittiAssociate(with[i], d, 0.5);
        const FrameAssociation y = KittiAssociate(without[i], d, 0.5);
        EXPECT_EQ(x.label_outcome, y.label_outcome);
        EXPECT_EQ(x.label_det, y.label_det);
        EXPECT_EQ(x.det_outcome, y.det_outcome);
        EXPECT_EQ(x.det_label, y.det_label);
      }
    }
  }
}

// The breakdown bins' (or a stable filter's) counts that KittiPasses makes in its pass 2 (SetBins)
// are, threshold by threshold, the sums over the frames of TallyBins on KittiAssociate's
// association at that threshold, which is what a bin's curve is defined by; counting them changes
// nothing of the unfiltered result; UseThresholds with the chosen thresholds gives the same counts.
TEST(KittiMatcherTest, PassTwoCountsBinsAsTallyBinsCountsTheAssociationAtEachThreshold) {
  RandomFramesOptions ro;
  ro.num_frames = 150;  // three blocks
  ro.seed = 33;
  ro.crowded = true;
  ro.score_decimals = 2;  // ties
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  const std::vector<Difficulty> all = {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard};
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<FilterCondition> filter = {{FilterBound::kMaxDistance, 10.0}};
  const std::vector<std::vector<StableSelection>> selection_sets = {
      {StableSelection::Bin(BreakdownAxis::kDistance, 0, 9),  // (crowded frames: z in [6, 14] m)
       StableSelection::Bin(BreakdownAxis::kDistance, 9, 11),
       StableSelection::Bin(BreakdownAxis::kDistance, 11, inf),
       StableSelection::Bin(BreakdownAxis::kHeight, 0, 120)},
      {StableSelection::Filter(filter)}};
  for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kLet3D}) {
    std::vector<ClassFrame> cfs;
    for (const EvalFrame& f : frames)
      cfs.push_back(PrepareClassFrame(f, KittiClassSpec("Car"), kind));
    for (const std::vector<StableSelection>& selections : selection_sets) {
      SCOPED_TRACE(std::string(OverlapKindName(kind)) + " " +
                   (selections.front().conditions ? "filter" : "bins"));
      const size_t n_s = selections.size();
      std::vector<BinMasks> masks;
      for (size_t i = 0; i < frames.size(); ++i)
        masks.push_back(MaskBins(frames[i], cfs[i], selections));
      auto run = [&](bool with_bins, const std::vector<std::vector<double>>* thresholds) {
        KittiPasses passes(cfs.size(), all);
        if (thresholds) {
          passes.UseThresholds(*thresholds);
        } else {
          for (size_t i = 0; i < cfs.size(); ++i) passes.CollectFrame(i, cfs[i]);
          passes.ChooseThresholds();
        }
        if (with_bins) passes.SetBins(&masks, n_s);
        for (size_t i = 0; i < cfs.size(); ++i) passes.CountFrame(i, cfs[i]);
        return passes.Finish();
      };
      const std::vector<KittiClassResult> plain = run(false, nullptr);
      const std::vector<KittiClassResult> got = run(true, nullptr);
      std::vector<std::vector<double>> chosen;
      for (const KittiClassResult& r : plain) chosen.push_back(r.thresholds);
      const std::vector<KittiClassResult> given = run(true, &chosen);
      std::vector<uint8_t> any_tp(n_s, 0), any_fp(n_s, 0);
      for (size_t d = 0; d < all.size(); ++d) {
        SCOPED_TRACE(DifficultyName(all[d]));
        const std::vector<double>& thresholds = plain[d].thresholds;
        ASSERT_FALSE(thresholds.empty());
        ASSERT_EQ(got[d].thresholds, thresholds);
        ASSERT_EQ(given[d].thresholds, thresholds);
        EXPECT_EQ(got[d].ap_r40, plain[d].ap_r40);
        EXPECT_EQ(got[d].aos_r40, plain[d].aos_r40);
        EXPECT_TRUE(plain[d].bin_counts.empty());
        ASSERT_EQ(got[d].bin_counts.size(), n_s);
        ASSERT_EQ(given[d].bin_counts.size(), n_s);
        for (size_t t = 0; t < thresholds.size(); ++t) {
          EXPECT_EQ(got[d].counts[t].tp, plain[d].counts[t].tp);
          EXPECT_EQ(got[d].counts[t].fp, plain[d].counts[t].fp);
          EXPECT_EQ(got[d].counts[t].similarity, plain[d].counts[t].similarity);
          std::vector<Tally> want(n_s);
          for (size_t i = 0; i < cfs.size(); ++i) {
            TallyBins(cfs[i], KittiAssociate(cfs[i], all[d], thresholds[t]), masks[i], n_s,
                      want.data());
          }
          for (size_t s = 0; s < n_s; ++s) {
            const KittiCounts& c = got[d].bin_counts[s][t];
            EXPECT_EQ(c.tp, want[s].tp) << t << " " << s;
            EXPECT_EQ(c.fp, want[s].fp) << t << " " << s;
            EXPECT_EQ(c.fn, want[s].fn) << t << " " << s;
            EXPECT_NEAR(c.similarity, want[s].similarity, 1e-9) << t << " " << s;
            const KittiCounts& g = given[d].bin_counts[s][t];
            EXPECT_EQ(g.tp, c.tp);
            EXPECT_EQ(g.fp, c.fp);
            EXPECT_EQ(g.fn, c.fn);
            EXPECT_EQ(g.similarity, c.similarity);
            any_tp[s] |= c.tp > 0;
            any_fp[s] |= c.fp > 0;
          }
        }
      }
      for (size_t s = 0; s < n_s; ++s) {  // every selection counts something
        EXPECT_TRUE(any_tp[s]) << s;
        EXPECT_TRUE(any_fp[s]) << s;
      }
    }
  }
}

}  // namespace
}  // namespace stereodet
