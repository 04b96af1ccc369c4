#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/curve_events_internal.h"
#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/frame_data_internal.h"
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

}  // namespace
}  // namespace stereodet
