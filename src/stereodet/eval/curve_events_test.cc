#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/curve_events_internal.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/frame_data_internal.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/selection_mask_internal.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

using testing_objects::Car2D;
using testing_objects::CarModerate2D;

// The optimal association re-pairs a label when a better detection arrives: label A (alpha 0) is
// first taken by a detection of alpha pi (similarity 0); at a lower score a detection that only
// fits A arrives while the first one also fits label B, so the maximum matching pairs both and the
// similarity of A's pair changes.
TEST(CurveEventsTest, OptimalSimilarityFollowsTheAssociationAtEachScore) {
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

// A component with more distinct scores than the exact AOS bound (256): the similarity is sampled
// at 64 scores, the lowest included, so the last curve point is still exact.
TEST(CurveEventsTest, HugeComponentIsSampledAndExactAtTheLowestScore) {
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
  const FrameAssociation a =
      Associate(Matcher::kOptimal, cf, Difficulty::kModerate, r.curve.back().threshold);
  double similarity = 0.0;
  for (int i = 0; i < cf.num_labels(); ++i) {
    ASSERT_EQ(a.label_outcome[i], Outcome::kTp);
    similarity += (1 + std::cos(cf.det_alpha[a.label_det[i]] - cf.label_alpha[i])) / 2;
  }
  EXPECT_NEAR(r.curve.back().similarity, similarity, 1e-9);
  EXPECT_LE(r.aos_r40, r.ap_r40 + 1e-9);
}

// Property, on random frames (crowded and not, tied scores) for every matcher, 2D and
// LET-3D, every difficulty: the breakdown bins' curves from AppendAssociationEvents (one
// association per distinct score that can change a pair, the lone false positives of the other
// scores counted from each detection's own fields) hold, at every score of the set, exactly the
// counts of tallying the matcher's association at that score (TallyBins), frame by frame.
TEST(CurveEventsTest, BinEventsGiveTheAssociationsCountsAtEveryScore) {
  const double inf = std::numeric_limits<double>::infinity();
  for (const bool crowded : {false, true}) {
    RandomFramesOptions ro;
    ro.num_frames = 60;
    ro.seed = crowded ? 8 : 9;
    ro.crowded = crowded;
    ro.score_decimals = 2;
    const std::vector<EvalFrame> frames = RandomFrames(ro);
    const double split = crowded ? 10.0 : 30.0;
    const std::vector<StableSelection> bins = {
        StableSelection::Bin(BreakdownAxis::kDistance, 0, split),
        StableSelection::Bin(BreakdownAxis::kDistance, split, inf),
        StableSelection::Bin(BreakdownAxis::kOcclusion, 0, 1)};
    const size_t n_s = bins.size();
    std::vector<double> scores;
    for (const EvalFrame& f : frames) {
      for (const Object& d : f.detections) scores.push_back(*d.score);
    }
    std::sort(scores.begin(), scores.end(), std::greater<double>());
    scores.erase(std::unique(scores.begin(), scores.end()), scores.end());
    for (const Matcher matcher : {Matcher::kOptimal, Matcher::kVoc, Matcher::kKitti}) {
      for (const OverlapKind kind : {OverlapKind::k2D, OverlapKind::kLet3D}) {
        std::vector<ClassFrame> cfs;
        std::vector<BinMasks> masks;
        for (const EvalFrame& f : frames) {
          cfs.push_back(
              PrepareClassFrame(f, KittiClassSpec("Car"), kind, OverlapArithmetic::kExact));
          masks.push_back(MaskBins(f, cfs.back(), bins));
        }
        for (const Difficulty d : {Difficulty::kEasy, Difficulty::kModerate, Difficulty::kHard}) {
          SCOPED_TRACE(std::string(MatcherName(matcher)) + " " + OverlapKindName(kind) + " " +
                       DifficultyName(d) + (crowded ? " crowded" : ""));
          std::vector<std::vector<CurveEvent>> events(n_s);
          std::vector<int64_t> base_fn(n_s, 0);
          for (size_t i = 0; i < cfs.size(); ++i) {
            AppendAssociationEvents(FrameAssociator(matcher, cfs[i], d), cfs[i], d, masks[i], n_s,
                                    /*with_aos=*/true, events.data(), base_fn.data());
          }
          std::vector<std::vector<CurvePoint>> curves;
          for (size_t s = 0; s < n_s; ++s) curves.push_back(BuildCurve(events[s], base_fn[s]));
          int64_t max_tp = 0;
          for (const double score : scores) {
            std::vector<Tally> want(n_s);
            for (size_t i = 0; i < cfs.size(); ++i) {
              TallyBins(cfs[i], Associate(matcher, cfs[i], d, score), masks[i], n_s, want.data());
            }
            for (size_t s = 0; s < n_s; ++s) {
              // The curve's last point at or above the score (descending thresholds).
              CurvePoint got;
              got.fn = base_fn[s];
              for (const CurvePoint& p : curves[s]) {
                if (p.threshold >= score) got = p;
              }
              ASSERT_EQ(got.tp, want[s].tp) << "score " << score << " bin " << s;
              ASSERT_EQ(got.fp, want[s].fp) << "score " << score << " bin " << s;
              ASSERT_EQ(got.fn, want[s].fn) << "score " << score << " bin " << s;
              ASSERT_NEAR(got.similarity, want[s].similarity, 1e-9) << "score " << score;
              max_tp = std::max(max_tp, got.tp);
            }
          }
          EXPECT_GT(max_tp, 0);  // the bins do hold pairs
        }
      }
    }
  }
}

}  // namespace
}  // namespace stereodet
