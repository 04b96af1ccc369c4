// TIDE-style error analysis (error_analysis.h): hand-computed cases under each matcher, KITTI's
// rules, properties on random frames, and TIDE's own classification and dAPs
// (tests/data/tide/tide_reference.csv, written by scripts/tide_reference_cases.py).
#include "stereodet/eval/error_analysis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"
#include "stereodet/util/strings.h"
#include "stereodet/util/test_paths.h"

namespace stereodet {
namespace {

using testing_objects::Det;
using testing_objects::Label;

constexpr int kCls = static_cast<int>(ErrorType::kCls);
constexpr int kLoc = static_cast<int>(ErrorType::kLoc);
constexpr int kBoth = static_cast<int>(ErrorType::kBoth);
constexpr int kDupe = static_cast<int>(ErrorType::kDupe);
constexpr int kBkg = static_cast<int>(ErrorType::kBkg);
constexpr int kMissed = static_cast<int>(ErrorType::kMissed);

// Car (0.7) and Pedestrian (0.5), 2D, Moderate.
EvalOptions CarPedestrian2D(Matcher matcher) {
  EvalOptions o;
  o.classes = {KittiClassSpec("Car"), KittiClassSpec("Pedestrian")};
  o.metrics = {OverlapKind::k2D};
  o.difficulties = {Difficulty::kModerate};
  o.matcher = matcher;
  o.num_threads = 2;
  return o;
}

ErrorAnalysis Analyze(const std::vector<EvalFrame>& frames, const EvalOptions& o,
                      const std::string& name) {
  return AnalyzeErrors(frames, o, KittiClassSpec(name), OverlapKind::k2D, Difficulty::kModerate);
}

// The AP of one cell of `frames` (2D, Moderate).
std::pair<double, double> CellAp(const std::vector<EvalFrame>& frames, const EvalOptions& o,
                                 const std::string& name) {
  EvalOptions c = o;
  c.classes = {KittiClassSpec(name)};
  c.require_detections = false;
  const ClassResult& r = Evaluate(frames, c).results.at(0);
  return {r.ap_r40, r.ap_r11};
}

const ClassifiedError* FindDetection(const ErrorClassification& c, int frame, int detection) {
  for (const ClassifiedError& e : c.errors) {
    if (e.frame == frame && e.detection == detection) return &e;
  }
  return nullptr;
}

// One frame with each error type once (boxes 100 px tall, shifted along x: IoU (100-s)/(100+s)).
//   labels: 0 Car [100,200] (found), 1 Car [300,400] (poorly localised), 2 Pedestrian [500,600],
//           3 Car [700,800] (missed), 4 Car [900,1000] (found), 5 Pedestrian [1100,1200]
//   Car detections, by score:
//     D0 .95 [100,200] TP on 0 (IoU 1)
//     D1 .90 [110,210] Dupe: IoU 90/110 = .818 >= .7 with label 0, which D0 took
//     D3 .85 [500,600] Cls: IoU 1 with the Pedestrian label 2 (>= its 0.5)
//     D4 .80 [1300,1400] Bkg: overlaps nothing
//     D2 .70 [320,420] Loc: IoU 80/120 = .667 with label 1, in [.1, .7); the label's only error
//     D6 .65 [900,1000] TP on 4
//     D5 .60 [1150,1250] Both: IoU 50/150 = .333 with the Pedestrian label 5, no Car label near
// 4 valid Car labels; FN: 1 (explained by D2's Loc) and 3 (Missed).
std::vector<EvalFrame> EveryTypeOnce() {
  EvalFrame f;
  f.id = "000000";
  f.labels = {
      Label("Car", {100, 100, 200, 200}),        Label("Car", {300, 100, 400, 200}),
      Label("Pedestrian", {500, 100, 600, 200}), Label("Car", {700, 100, 800, 200}),
      Label("Car", {900, 100, 1000, 200}),       Label("Pedestrian", {1100, 100, 1200, 200})};
  f.detections = {
      Det("Car", {100, 100, 200, 200}, 0.95),   Det("Car", {110, 100, 210, 200}, 0.90),
      Det("Car", {320, 100, 420, 200}, 0.70),   Det("Car", {500, 100, 600, 200}, 0.85),
      Det("Car", {1300, 100, 1400, 200}, 0.80), Det("Car", {1150, 100, 1250, 200}, 0.60),
      Det("Car", {900, 100, 1000, 200}, 0.65)};
  return {f};
}

class ErrorAnalysisExactMatcherTest : public ::testing::TestWithParam<Matcher> {};

// The exact matchers (optimal, VOC) agree on this frame; their AP_R40 is the mean over r = k/40 of
// max{P : R >= r}, AP_R11 over r = 0, .1, ..., 1.
TEST_P(ErrorAnalysisExactMatcherTest, EveryTypeOnceByHand) {
  const std::vector<EvalFrame> frames = EveryTypeOnce();
  const EvalOptions o = CarPedestrian2D(GetParam());
  const ErrorClassification c = ClassifyErrors(frames, o, OverlapKind::k2D, Difficulty::kModerate);
  const ErrorType want[] = {ErrorType::kDupe, ErrorType::kLoc, ErrorType::kCls, ErrorType::kBkg,
                            ErrorType::kBoth};
  const int want_det[] = {1, 2, 3, 4, 5};
  const int want_label[] = {0, 1, 2, -1, 5};
  for (int x = 0; x < 5; ++x) {
    const ClassifiedError* e = FindDetection(c, 0, want_det[x]);
    ASSERT_NE(e, nullptr) << want_det[x];
    EXPECT_EQ(e->type, want[x]) << "D" << want_det[x] << ": " << ErrorTypeName(e->type);
    EXPECT_EQ(e->label, want_label[x]) << want_det[x];
  }
  EXPECT_NEAR(FindDetection(c, 0, 1)->overlap, 90.0 / 110.0, 1e-12);
  EXPECT_NEAR(FindDetection(c, 0, 2)->overlap, 80.0 / 120.0, 1e-12);
  EXPECT_TRUE(FindDetection(c, 0, 2)->fixable);  // the only error on label 1
  EXPECT_EQ(FindDetection(c, 0, 3)->target_class, 1);
  EXPECT_TRUE(FindDetection(c, 0, 3)->fixable);  // Pedestrian label 2 is unused
  EXPECT_EQ(FindDetection(c, 0, 0), nullptr);    // TPs get no type
  EXPECT_EQ(FindDetection(c, 0, 6), nullptr);

  const ErrorAnalysis a = Analyze(frames, o, "Car");
  EXPECT_TRUE(a.evaluated);
  EXPECT_EQ(a.num_valid_labels, 4);
  EXPECT_EQ(a.tp, 2);
  EXPECT_EQ(a.fp, 5);
  EXPECT_EQ(a.fn, 2);
  for (int t = 0; t < kNumErrorTypes; ++t) EXPECT_EQ(a.count[t], 1) << t;
  EXPECT_EQ(a.cls_incoming, 0);
  // As is: TP at .95 (P 1, R .25), FPs at .90 .85 .80 .70, TP at .65 (P 2/6, R .5), FP at .60.
  // AP_R40 = (10 x 1 + 10 x 1/3) / 40 = 33.33; AP_R11 = (3 x 1 + 3 x 1/3) / 11 = 36.36.
  EXPECT_NEAR(a.ap_r40, 100.0 / 3.0, 1e-9);
  EXPECT_NEAR(a.ap_r11, 400.0 / 11.0, 1e-9);
  // Dupe, Cls, Bkg: one FP above .65 fewer: P(.65) = 2/5: AP_R40 (10 + 4) / 40 = 35,
  // AP_R11 (3 + 1.2) / 11 = 38.18.
  for (const int t : {kDupe, kCls, kBkg}) {
    EXPECT_NEAR(a.delta_ap_r40[t], 35.0 - 100.0 / 3.0, 1e-9) << t;
    EXPECT_NEAR(a.delta_ap_r11[t], 420.0 / 11.0 - 400.0 / 11.0, 1e-9) << t;
  }
  // Both: D5 is below the last TP: nothing changes.
  EXPECT_NEAR(a.delta_ap_r40[kBoth], 0.0, 1e-9);
  EXPECT_NEAR(a.delta_ap_r11[kBoth], 0.0, 1e-9);
  // Loc: D2 moved onto label 1, a TP at .70 (P 2/5, R .5), then .65 (P 3/6, R .75):
  // AP_R40 (10 + 20 x .5) / 40 = 50, AP_R11 (3 + 5 x .5) / 11 = 50.
  EXPECT_NEAR(a.delta_ap_r40[kLoc], 50.0 - 100.0 / 3.0, 1e-9);
  EXPECT_NEAR(a.delta_ap_r11[kLoc], 50.0 - 400.0 / 11.0, 1e-9);
  // Missed: label 3 gone, 3 labels: R 1/3 at .95, (P 1/3, R 2/3) at .65:
  // AP_R40 (13 + 13 / 3) / 40 = 43.33, AP_R11 (4 + 3 / 3) / 11 = 45.45.
  EXPECT_NEAR(a.delta_ap_r40[kMissed], 10.0, 1e-9);
  EXPECT_NEAR(a.delta_ap_r11[kMissed], 500.0 / 11.0 - 400.0 / 11.0, 1e-9);
  // FP: only D0 and D6, (P 1, R .5): AP_R40 20 / 40 = 50, AP_R11 6 / 11 = 54.55.
  EXPECT_NEAR(a.delta_fp_r40, 50.0 - 100.0 / 3.0, 1e-9);
  EXPECT_NEAR(a.delta_fp_r11, 600.0 / 11.0 - 400.0 / 11.0, 1e-9);
  // FN: labels 1 and 3 gone: (P 1, R .5) at .95, (P 1/3, R 1) at .65:
  // AP_R40 (20 + 20 / 3) / 40 = 66.67, AP_R11 (6 + 5 / 3) / 11 = 69.70.
  EXPECT_NEAR(a.delta_fn_r40, 200.0 / 3.0 - 100.0 / 3.0, 1e-9);
  EXPECT_NEAR(a.delta_fn_r11, (6.0 + 5.0 / 3.0) / 11.0 * 100.0 - 400.0 / 11.0, 1e-9);

  // The Pedestrian cell: label 2 is explained by Car D3's Cls error, label 5 is missed (D5 is a
  // Both error, which explains no label, as in TIDE). It has no detection, so Evaluate does not
  // evaluate it (require_detections) ...
  const ErrorAnalysis p = Analyze(frames, o, "Pedestrian");
  EXPECT_FALSE(p.evaluated);
  EXPECT_TRUE(std::isnan(p.ap_r40));
  EXPECT_EQ(p.count[kMissed], 1);
  EXPECT_EQ(p.cls_incoming, 1);
  EXPECT_EQ(p.fn, 2);
  // ... unless asked to: fixing Cls relabels D3 to Pedestrian, a TP at .85 on 2 labels: 50.
  EvalOptions all = o;
  all.require_detections = false;
  const ErrorAnalysis q = Analyze(frames, all, "Pedestrian");
  EXPECT_TRUE(q.evaluated);
  EXPECT_EQ(q.ap_r40, 0.0);
  EXPECT_NEAR(q.delta_ap_r40[kCls], 50.0, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(ErrorAnalysisExact, ErrorAnalysisExactMatcherTest,
                         ::testing::Values(Matcher::kOptimal, Matcher::kVoc),
                         [](const auto& info) { return std::string(MatcherName(info.param)); });

// The same frame under the KITTI matcher: the same types (no ambiguity in its association), AP in
// the devkit's 41-slot arithmetic. Pass 1 keeps the TP scores .95 and .65 as thresholds (4
// labels): precision 1 at .95, 2/6 at .65 (D5 at .60 is below the last threshold), slots 0 and 1.
// AP_R40 = slot 1 / 40 = (1/3) / 40 = 0.833; AP_R11 = slot 0 / 11 = 9.09 (the small-sample cap).
TEST(ErrorAnalysisTest, EveryTypeOnceUnderTheKittiMatcherByHand) {
  const std::vector<EvalFrame> frames = EveryTypeOnce();
  const ErrorAnalysis a = Analyze(frames, CarPedestrian2D(Matcher::kKitti), "Car");
  for (int t = 0; t < kNumErrorTypes; ++t) EXPECT_EQ(a.count[t], 1) << t;
  EXPECT_NEAR(a.ap_r40, 100.0 / 120.0, 1e-9);
  EXPECT_NEAR(a.ap_r11, 100.0 / 11.0, 1e-9);
  // Dupe, Cls, Bkg: slot 1 = 2/5: AP_R40 = 1.0, + 1/6; slot 0 unchanged.
  for (const int t : {kDupe, kCls, kBkg}) {
    EXPECT_NEAR(a.delta_ap_r40[t], 1.0 - 100.0 / 120.0, 1e-9) << t;
    EXPECT_NEAR(a.delta_ap_r11[t], 0.0, 1e-9) << t;
  }
  EXPECT_NEAR(a.delta_ap_r40[kBoth], 0.0, 1e-9);
  // Loc: D2 on label 1 adds the threshold .70: slots 1, 2 = max(2/5, 3/6) = 1/2 after the
  // envelope: AP_R40 = 1 / 40 = 2.5.
  EXPECT_NEAR(a.delta_ap_r40[kLoc], 2.5 - 100.0 / 120.0, 1e-9);
  // Missed and FN: 3 or 2 labels keep the two thresholds and their precisions: nothing changes.
  EXPECT_NEAR(a.delta_ap_r40[kMissed], 0.0, 1e-9);
  EXPECT_NEAR(a.delta_fn_r40, 0.0, 1e-9);
  // FP: slot 1 = 1: AP_R40 2.5.
  EXPECT_NEAR(a.delta_fp_r40, 2.5 - 100.0 / 120.0, 1e-9);
}

// Two crowded Car labels, l0 [100,200] and l1 [120,220] (IoU .667), and two detections:
// d0 [105,205] .9 (IoU .905 with l0, .739 with l1), d1 [90,190] .8 (IoU .818 with l0, .538 with
// l1). The KITTI matcher (l0 first takes its largest overlap, d0; l1 has nothing left) and VOC (d0
// to its best label l0, d1's best label l0 taken) leave d1 a Dupe of l0 and l1 missed; the
// optimal matcher pairs l0-d1, l1-d0: no error at all.
TEST(ErrorAnalysisTest, DupesDifferBetweenTheKittiAndTheOptimalMatcher) {
  EvalFrame f;
  f.id = "000001";
  f.labels = {Label("Car", {100, 100, 200, 200}), Label("Car", {120, 100, 220, 200})};
  f.detections = {Det("Car", {105, 100, 205, 200}, 0.9), Det("Car", {90, 100, 190, 200}, 0.8)};
  const std::vector<EvalFrame> frames = {f};
  for (const Matcher m : {Matcher::kKitti, Matcher::kVoc}) {
    const ErrorClassification c =
        ClassifyErrors(frames, CarPedestrian2D(m), OverlapKind::k2D, Difficulty::kModerate);
    ASSERT_EQ(c.errors.size(), 2u) << MatcherName(m);
    EXPECT_EQ(c.errors[0].type, ErrorType::kDupe);
    EXPECT_EQ(c.errors[0].detection, 1);
    EXPECT_EQ(c.errors[0].label, 0);
    EXPECT_NEAR(c.errors[0].overlap, 90.0 / 110.0, 1e-12);
    EXPECT_EQ(c.errors[1].type, ErrorType::kMissed);
    EXPECT_EQ(c.errors[1].label, 1);
  }
  const ErrorClassification c = ClassifyErrors(frames, CarPedestrian2D(Matcher::kOptimal),
                                               OverlapKind::k2D, Difficulty::kModerate);
  EXPECT_TRUE(c.errors.empty());
  const ErrorAnalysis a = Analyze(frames, CarPedestrian2D(Matcher::kOptimal), "Car");
  EXPECT_EQ(a.ap_r40, 100.0);
  for (int t = 0; t < kNumErrorTypes; ++t) EXPECT_EQ(a.delta_ap_r40[t], 0.0);
  // KITTI: pass 1 gives l0 to d0 (highest score), one threshold .9 on 2 labels: AP_R40 0 (slot 0
  // only), AP_R11 9.09; removing the dupe or the missed label keeps that threshold: dAP 0.
  const ErrorAnalysis k = Analyze(frames, CarPedestrian2D(Matcher::kKitti), "Car");
  EXPECT_EQ(k.count[kDupe], 1);
  EXPECT_EQ(k.count[kMissed], 1);
  EXPECT_NEAR(k.ap_r11, 100.0 / 11.0, 1e-9);
  EXPECT_NEAR(k.delta_ap_r40[kDupe], 0.0, 1e-9);
  EXPECT_NEAR(k.delta_ap_r40[kMissed], 0.0, 1e-9);
}

// A Dupe that scores above its label's TP. l0 [100,200], l1 [130,230]; e [115,215] .9 (IoU .739
// with both), d [83,183] .5 (IoU .709 with l0, .36 with l1), f [130,230] .3 (IoU 1 with l1, .538
// with l0), g far away .4. With every detection present both matchers pair l0-e, l1-f (optimal:
// IoU sum 1.739 against 1.709 for l0-d, l1-f; KITTI: l0 takes its largest overlap, e), so d is a
// Dupe of l0. But at threshold .5 (d, e present) the optimal matcher needs d: l0-d, l1-e.
//   optimal as is: (P 1, R .5) at .9, (1, 1) at .5, (2/3, 1) at .4, (1/2, 1) at .3: AP 100.
//   d removed: (1, .5) at .9, (1/2, 1/2) at .4, (2/3, 1) at .3: AP_R40 (20 + 20 x 2/3) / 40 =
//   83.33, AP_R11 (6 + 5 x 2/3) / 11 = 84.85: dAP -16.67 / -15.15 (TIDE would clamp it at 0).
//   KITTI as is: pass 1 thresholds .9 (e on l0) and .3 (f on l1); precision 1 at .9, 2/4 at .3:
//   AP_R40 = .5 / 40 = 1.25. d removed: 2/3 at .3: AP_R40 1.667, dAP + .4167.
TEST(ErrorAnalysisTest, RemovingAHigherScoringDupeCanLowerTheAp) {
  EvalFrame fr;
  fr.id = "000002";
  fr.labels = {Label("Car", {100, 100, 200, 200}), Label("Car", {130, 100, 230, 200})};
  fr.detections = {Det("Car", {115, 100, 215, 200}, 0.9), Det("Car", {83, 100, 183, 200}, 0.5),
                   Det("Car", {130, 100, 230, 200}, 0.3), Det("Car", {1000, 100, 1100, 200}, 0.4)};
  const std::vector<EvalFrame> frames = {fr};
  for (const Matcher m : {Matcher::kKitti, Matcher::kOptimal}) {
    const ErrorClassification c =
        ClassifyErrors(frames, CarPedestrian2D(m), OverlapKind::k2D, Difficulty::kModerate);
    const ClassifiedError* d = FindDetection(c, 0, 1);
    ASSERT_NE(d, nullptr) << MatcherName(m);
    EXPECT_EQ(d->type, ErrorType::kDupe) << MatcherName(m);
    EXPECT_EQ(d->label, 0);
    EXPECT_EQ(FindDetection(c, 0, 3)->type, ErrorType::kBkg);
  }
  const ErrorAnalysis o = Analyze(frames, CarPedestrian2D(Matcher::kOptimal), "Car");
  EXPECT_NEAR(o.ap_r40, 100.0, 1e-9);
  EXPECT_NEAR(o.delta_ap_r40[kDupe], 250.0 / 3.0 - 100.0, 1e-9);
  EXPECT_NEAR(o.delta_ap_r11[kDupe], (6.0 + 10.0 / 3.0) / 11.0 * 100.0 - 100.0, 1e-9);
  const ErrorAnalysis k = Analyze(frames, CarPedestrian2D(Matcher::kKitti), "Car");
  EXPECT_NEAR(k.ap_r40, 1.25, 1e-9);
  EXPECT_NEAR(k.delta_ap_r40[kDupe], 2.0 / 3.0 / 40.0 * 100.0 - 1.25, 1e-9);
}

// Cls errors of another class fix this class's labels, and Loc and Cls errors on one label
// compete (TIDE's BestGTMatch): Car labels c0 [100,200] (found by a .9) and c1 [300,400]; Car b
// [330,430] (IoU .538 with c1: Loc) and Pedestrian p exactly on c1 (Cls, at Car's 0.7).
TEST(ErrorAnalysisTest, LocAndClsErrorsCompeteForAnUnusedLabel) {
  for (const double b_score : {0.5, 0.85}) {
    EvalFrame f;
    f.id = "000003";
    f.labels = {Label("Car", {100, 100, 200, 200}), Label("Car", {300, 100, 400, 200})};
    f.detections = {Det("Car", {100, 100, 200, 200}, 0.9),
                    Det("Car", {330, 100, 430, 200}, b_score),
                    Det("Pedestrian", {300, 100, 400, 200}, 0.8)};
    const std::vector<EvalFrame> frames = {f};
    const EvalOptions o = CarPedestrian2D(Matcher::kOptimal);
    const ErrorClassification c =
        ClassifyErrors(frames, o, OverlapKind::k2D, Difficulty::kModerate);
    const ClassifiedError* b = FindDetection(c, 0, 1);
    const ClassifiedError* p = FindDetection(c, 0, 2);
    ASSERT_TRUE(b != nullptr && p != nullptr);
    EXPECT_EQ(b->type, ErrorType::kLoc);
    EXPECT_EQ(p->type, ErrorType::kCls);
    EXPECT_EQ(p->class_index, 1);
    EXPECT_EQ(p->target_class, 0);
    EXPECT_EQ(b->label, 1);
    EXPECT_EQ(p->label, 1);
    const bool b_wins = b_score > 0.8;
    EXPECT_EQ(b->fixable, b_wins);
    EXPECT_EQ(p->fixable, !b_wins);
    const ErrorAnalysis a = Analyze(frames, o, "Car");
    EXPECT_EQ(a.count[kMissed], 0);  // c1 is explained either way
    EXPECT_EQ(a.count[kLoc], 1);
    EXPECT_EQ(a.cls_incoming, b_wins ? 0 : 1);
    if (b_wins) {
      // As is (1, .5) at .9, (1/2, .5) at .85: AP_R40 50. Loc moves b onto c1: 100. Cls removes
      // p from the Pedestrians, which changes nothing for Car.
      EXPECT_NEAR(a.ap_r40, 50.0, 1e-9);
      EXPECT_NEAR(a.delta_ap_r40[kLoc], 50.0, 1e-9);
      EXPECT_NEAR(a.delta_ap_r40[kCls], 0.0, 1e-9);
    } else {
      // Loc removes b (not its label's winner): (1, .5) only: 50, dAP 0. Cls makes p a Car TP at
      // .8: (1, .5), (1, 1), (2/3, 1): AP_R40 100, AP_R11 100 (as is 6 / 11 = 54.55).
      EXPECT_NEAR(a.ap_r40, 50.0, 1e-9);
      EXPECT_NEAR(a.delta_ap_r40[kLoc], 0.0, 1e-9);
      EXPECT_NEAR(a.delta_ap_r40[kCls], 50.0, 1e-9);
      EXPECT_NEAR(a.delta_ap_r11[kCls], 100.0 - 600.0 / 11.0, 1e-9);
    }
    // Both fixed together: the winner becomes c1's TP, the other is removed: AP 100.
    const std::vector<EvalFrame> fixed =
        FixErrors(frames, c, 0, {ErrorType::kLoc, ErrorType::kCls});
    EXPECT_NEAR(CellAp(fixed, o, "Car").first, 100.0, 1e-9);
  }
}

// KITTI's rules: neighbour classes, DontCare regions and labels that fail the difficulty are not
// errors; an ignored label absorbs one detection in the KITTI matcher (a second one is a Dupe)
// and any number in the optimal matcher; an overlap exactly at the threshold is a Loc error for
// the devkit (> tau) and a TP for the optimal matcher (>= tau).
TEST(ErrorAnalysisTest, KittiRulesDecideWhatIsAnError) {
  EvalFrame f;
  f.id = "000004";
  f.labels = {Label("Van", {100, 100, 200, 200}), Label("DontCare", {300, 100, 500, 200}),
              Label("Pedestrian", {600, 100, 700, 200}),
              Label("Car", {800, 100, 900, 200}, /*truncated=*/0, /*occluded=*/2),  // Hard only
              Label("Van", {1000, 100, 1100, 200})};
  f.detections = {Det("Car", {100, 100, 200, 200}, 0.9),     // 0: on the Van: ignored
                  Det("Car", {105, 100, 205, 200}, 0.8),     // 1: on the Van again
                  Det("Car", {350, 120, 450, 180}, 0.7),     // 2: in the DontCare region
                  Det("Car", {600, 100, 700, 200}, 0.6),     // 3: on a Pedestrian (not analysed)
                  Det("Car", {800, 100, 900, 200}, 0.5),     // 4: on the Hard-only Car: ignored
                  Det("Car", {1050, 100, 1150, 200}, 0.4)};  // 5: IoU 1/3 with the second Van
  EvalOptions o = CarPedestrian2D(Matcher::kKitti);
  o.classes = {KittiClassSpec("Car")};
  const ErrorClassification k = ClassifyErrors({f}, o, OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_EQ(k.errors.size(), 3u);
  EXPECT_EQ(k.errors[0].detection, 1);
  EXPECT_EQ(k.errors[0].type, ErrorType::kDupe);
  EXPECT_EQ(k.errors[0].label, 0);
  EXPECT_EQ(k.errors[1].detection, 3);
  EXPECT_EQ(k.errors[1].type, ErrorType::kCls);
  EXPECT_EQ(k.errors[1].target_class, -1);
  EXPECT_FALSE(k.errors[1].fixable);
  EXPECT_EQ(k.errors[2].detection, 5);
  EXPECT_EQ(k.errors[2].type, ErrorType::kLoc);
  EXPECT_EQ(k.errors[2].label, 4);
  EXPECT_FALSE(k.errors[2].fixable);  // an ignored label: its fix removes the detection
  EXPECT_TRUE(k.false_negatives.empty());
  o.matcher = Matcher::kOptimal;
  const ErrorClassification opt = ClassifyErrors({f}, o, OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_EQ(opt.errors.size(), 2u);  // the Van excuses both detections on it
  EXPECT_EQ(opt.errors[0].type, ErrorType::kCls);
  EXPECT_EQ(opt.errors[1].type, ErrorType::kLoc);

  // IoU exactly 0.5 for a Pedestrian (records_test's pair): KITTI Loc (fixable), optimal TP.
  EvalFrame g;
  g.id = "000005";
  g.labels = {Label("Pedestrian", {900, 100, 1000, 200})};
  g.detections = {Det("Pedestrian", {950, 100, 1000, 200}, 0.5)};
  o.classes = {KittiClassSpec("Pedestrian")};
  o.matcher = Matcher::kKitti;
  const ErrorClassification gk = ClassifyErrors({g}, o, OverlapKind::k2D, Difficulty::kModerate);
  ASSERT_EQ(gk.errors.size(), 1u);
  EXPECT_EQ(gk.errors[0].type, ErrorType::kLoc);
  EXPECT_TRUE(gk.errors[0].fixable);
  EXPECT_EQ(gk.errors[0].overlap, 0.5);
  o.matcher = Matcher::kOptimal;
  EXPECT_TRUE(ClassifyErrors({g}, o, OverlapKind::k2D, Difficulty::kModerate).errors.empty());
}

TEST(ErrorAnalysisTest, OptionsAndNamesAreChecked) {
  ErrorAnalysisOptions ea;
  EXPECT_NO_THROW(ea.Check());
  for (const double bad : {0.0, -0.1, 1.0, std::nan("")}) {
    ea.background_overlap = bad;
    EXPECT_THROW(ea.Check(), std::invalid_argument) << bad;
  }
  const std::vector<EvalFrame> frames = EveryTypeOnce();
  EvalOptions o = CarPedestrian2D(Matcher::kKitti);
  ea.background_overlap = 0.6;  // above Pedestrian's 0.5
  EXPECT_THROW(ClassifyErrors(frames, o, OverlapKind::k2D, Difficulty::kModerate, ea),
               std::invalid_argument);
  o.compat = EvalCompat::kOpenPcdet;
  EXPECT_THROW(ClassifyErrors(frames, o, OverlapKind::k2D, Difficulty::kModerate),
               std::invalid_argument);
  o = CarPedestrian2D(Matcher::kKitti);
  o.classes.push_back(KittiClassSpec("car"));
  EXPECT_THROW(ClassifyErrors(frames, o, OverlapKind::k2D, Difficulty::kModerate),
               std::invalid_argument);
  const ErrorClassification c = ClassifyErrors(frames, CarPedestrian2D(Matcher::kKitti),
                                               OverlapKind::k2D, Difficulty::kModerate);
  EXPECT_THROW(FixErrors(frames, c, 2, {ErrorType::kLoc}), std::invalid_argument);
  EXPECT_THROW(FixErrors({}, c, 0, {ErrorType::kLoc}), std::invalid_argument);
  for (int t = 0; t < kNumErrorTypes; ++t) {
    const ErrorType type = static_cast<ErrorType>(t);
    EXPECT_EQ(ParseErrorType(ErrorTypeName(type)), type);
  }
  EXPECT_EQ(ParseErrorType("Dupe"), ErrorType::kDupe);
  EXPECT_FALSE(ParseErrorType("other").has_value());
}

// ---------------------------------------------------------------------------------------------
// Properties on random frames.

struct RandomCase {
  Matcher matcher;
  OverlapKind kind;
  bool crowded;
  uint64_t seed;
};

std::vector<EvalFrame> Frames(const RandomCase& rc) {
  RandomFramesOptions ro;
  ro.num_frames = rc.crowded ? 40 : 80;
  ro.crowded = rc.crowded;
  ro.seed = rc.seed;
  ro.score_decimals = rc.seed % 2 == 0 ? 2 : 0;  // ties in half of them
  std::vector<EvalFrame> frames = RandomFrames(ro);
  // RandomFrames' detections have their object's class; one in nine gets another one (Car ->
  // Pedestrian -> Cyclist -> Car), the class confusions of Cls errors.
  const std::string next[][2] = {
      {"Car", "Pedestrian"}, {"Pedestrian", "Cyclist"}, {"Cyclist", "Car"}};
  int n = 0;
  for (EvalFrame& f : frames) {
    for (Object& d : f.detections) {
      if (n++ % 9 != 4) continue;
      for (const auto& [from, to] : next) {
        if (d.type == from) {
          d.type = to;
          break;
        }
      }
    }
  }
  return frames;
}

bool OwnLabel(const std::string& type, const ClassSpec& spec) {
  if (EqualsIgnoreCase(type, spec.name)) return true;
  for (const std::string& n : spec.neighbours) {
    if (EqualsIgnoreCase(type, n)) return true;
  }
  return false;
}

// The options of a random case: its matcher and overlap kind, Moderate, two threads.
EvalOptions OptionsOf(const RandomCase& rc) {
  EvalOptions o;
  o.matcher = rc.matcher;
  o.metrics = {rc.kind};
  o.difficulties = {Difficulty::kModerate};
  o.num_threads = 2;
  return o;
}

class ErrorAnalysisPropertyTest : public ::testing::TestWithParam<RandomCase> {};
class ErrorAnalysisFixPropertyTest : public ::testing::TestWithParam<RandomCase> {};

// Every FP detection gets exactly one type, consistent with its definition; the FNs are the
// missed labels plus the explained ones, each explained label has one winner; the analysis' AP is
// Evaluate's.
TEST_P(ErrorAnalysisPropertyTest, TypesPartitionTheFalsePositivesAndNegatives) {
  const RandomCase rc = GetParam();
  const std::vector<EvalFrame> frames = Frames(rc);
  const EvalOptions o = OptionsOf(rc);
  const ErrorClassification c = ClassifyErrors(frames, o, rc.kind, Difficulty::kModerate);
  const EvalResult plain = Evaluate(frames, o);
  const int kind = static_cast<int>(rc.kind);
  std::set<std::pair<int, int>> seen_dets;
  std::map<std::tuple<int, int>, int> winners;  // (frame, label) -> fixable errors on it
  for (const ClassifiedError& e : c.errors) {
    if (e.type == ErrorType::kMissed) continue;
    EXPECT_TRUE(seen_dets.insert({e.frame, e.detection}).second) << "twice: " << e.detection;
    const ClassSpec& spec = c.classes[e.class_index];
    const double t_f = spec.min_overlap[kind];
    const EvalFrame& f = frames[e.frame];
    EXPECT_TRUE(EqualsIgnoreCase(f.detections[e.detection].type, spec.name));
    if (e.fixable) ++winners[{e.frame, e.label}];
    switch (e.type) {
      case ErrorType::kLoc:
        EXPECT_TRUE(OwnLabel(f.labels[e.label].type, spec));
        EXPECT_GE(e.overlap, c.background_overlap);
        EXPECT_LE(e.overlap, t_f);
        break;
      case ErrorType::kDupe:
        EXPECT_TRUE(OwnLabel(f.labels[e.label].type, spec));
        EXPECT_GE(e.overlap, t_f);
        break;
      case ErrorType::kCls:
        EXPECT_FALSE(OwnLabel(f.labels[e.label].type, spec));
        EXPECT_GE(e.overlap, std::min(t_f, 0.5));
        break;
      case ErrorType::kBoth:
        EXPECT_FALSE(OwnLabel(f.labels[e.label].type, spec));
        EXPECT_GT(e.overlap, c.background_overlap);
        break;
      case ErrorType::kBkg:
        EXPECT_LE(e.overlap, c.background_overlap);
        break;
      case ErrorType::kMissed:
        break;
    }
    if (e.type != ErrorType::kLoc && e.type != ErrorType::kCls) {
      EXPECT_FALSE(e.fixable);
    }
  }
  for (const auto& [key, n] : winners) EXPECT_EQ(n, 1);
  for (size_t k = 0; k < c.classes.size(); ++k) {
    const std::array<int64_t, kNumErrorTypes> n = c.Count(static_cast<int>(k));
    const ClassResult& cell = c.cells[k];
    EXPECT_EQ(n[kCls] + n[kLoc] + n[kBoth] + n[kDupe] + n[kBkg], cell.at_threshold.fp)
        << c.classes[k].name;
    EXPECT_LE(n[kMissed], cell.at_threshold.fn);
    int64_t fn = 0, explained = 0;
    for (const UnmatchedLabel& u : c.false_negatives) {
      if (u.class_index != static_cast<int>(k)) continue;
      ++fn;
      if (!u.missed) {
        ++explained;
        EXPECT_EQ(winners.count({u.frame, u.label}), 1u);
      }
    }
    EXPECT_EQ(fn, cell.at_threshold.fn);
    EXPECT_EQ(fn - explained, n[kMissed]);
    // The cell as is equals Evaluate's.
    const ClassResult* r = plain.Find(c.classes[k].name, rc.kind, Difficulty::kModerate);
    ASSERT_NE(r, nullptr);
    if (r->evaluated) {
      EXPECT_EQ(cell.ap_r40, r->ap_r40);
      EXPECT_EQ(cell.ap_r11, r->ap_r11);
    }
  }
}

// Fixing what the exact matchers allow to be said exactly: with the optimal matcher, every type
// fixed gives AP 100 (every FP removed or turned into its label's TP, every FN explained and
// fixed or removed), no FP gives precision 1 at every curve point, no FN recall 1 at the lowest
// score; with VOC (an FP takes no label, so removing one changes nobody else) removing Dupe, Bkg
// or Both errors or every FP never lowers the AP.
TEST_P(ErrorAnalysisFixPropertyTest, FixesDoWhatTheyShould) {
  const RandomCase rc = GetParam();
  const std::vector<EvalFrame> frames = Frames(rc);
  const EvalOptions o = OptionsOf(rc);
  const ErrorClassification c = ClassifyErrors(frames, o, rc.kind, Difficulty::kModerate);
  for (size_t k = 0; k < c.classes.size(); ++k) {
    EvalOptions one = o;
    one.classes = {c.classes[k]};
    one.require_detections = false;
    auto cell = [&](const std::vector<EvalFrame>& fr) { return Evaluate(fr, one).results.at(0); };
    const std::string& name = c.classes[k].name;
    if (rc.matcher == Matcher::kOptimal) {
      const ClassResult all =
          cell(FixErrors(frames, c, static_cast<int>(k),
                         {ErrorType::kCls, ErrorType::kLoc, ErrorType::kBoth, ErrorType::kDupe,
                          ErrorType::kBkg, ErrorType::kMissed}));
      if (all.num_valid_labels > 0) {
        EXPECT_EQ(all.ap_r40, 100.0) << name;
        EXPECT_EQ(all.ap_r11, 100.0) << name;
        EXPECT_EQ(all.at_threshold.fp, 0) << name;
        EXPECT_EQ(all.at_threshold.fn, 0) << name;
      }
      const ClassResult no_fp =
          cell(FixSpecialError(frames, c, static_cast<int>(k), SpecialError::kFalsePositives));
      for (const CurvePoint& p : no_fp.curve) EXPECT_EQ(p.fp, 0) << name << " " << p.threshold;
      const ClassResult no_fn =
          cell(FixSpecialError(frames, c, static_cast<int>(k), SpecialError::kFalseNegatives));
      if (!no_fn.curve.empty() && no_fn.num_valid_labels > 0) {
        EXPECT_EQ(no_fn.curve.back().fn, 0) << name;
      }
    } else {
      const ClassResult as_is = c.cells[k];
      for (const ErrorType t : {ErrorType::kDupe, ErrorType::kBkg, ErrorType::kBoth}) {
        const ClassResult fixed = cell(FixErrors(frames, c, static_cast<int>(k), {t}));
        EXPECT_GE(fixed.ap_r40, as_is.ap_r40 - 1e-9) << name << " " << ErrorTypeName(t);
        EXPECT_GE(fixed.ap_r11, as_is.ap_r11 - 1e-9) << name << " " << ErrorTypeName(t);
        EXPECT_EQ(fixed.at_threshold.tp, as_is.at_threshold.tp) << name;
      }
      const ClassResult no_fp =
          cell(FixSpecialError(frames, c, static_cast<int>(k), SpecialError::kFalsePositives));
      EXPECT_GE(no_fp.ap_r40, as_is.ap_r40 - 1e-9) << name;
    }
  }
}

std::vector<RandomCase> RandomCases(const std::vector<Matcher>& matchers) {
  std::vector<RandomCase> out;
  uint64_t seed = 11;
  for (const Matcher m : matchers) {
    for (const OverlapKind kind :
         {OverlapKind::k2D, OverlapKind::kBev, OverlapKind::k3D, OverlapKind::kLetBev}) {
      for (const bool crowded : {false, true}) out.push_back({m, kind, crowded, seed++});
    }
  }
  return out;
}

std::string RandomCaseName(const ::testing::TestParamInfo<RandomCase>& info) {
  const RandomCase& rc = info.param;
  std::string kind = OverlapKindName(rc.kind);
  std::replace(kind.begin(), kind.end(), '-', '_');
  return std::string(MatcherName(rc.matcher)) + "_" + kind + (rc.crowded ? "_crowded" : "");
}

INSTANTIATE_TEST_SUITE_P(ErrorAnalysisRandom, ErrorAnalysisPropertyTest,
                         ::testing::ValuesIn(RandomCases({Matcher::kKitti, Matcher::kOptimal,
                                                          Matcher::kVoc})),
                         RandomCaseName);
// The devkit's AP has no such guarantees (its thresholds come from pass 1, its precision slots
// from pass 2; a moved or relabelled detection can be taken by an earlier label in file order).
INSTANTIATE_TEST_SUITE_P(ErrorAnalysisRandom, ErrorAnalysisFixPropertyTest,
                         ::testing::ValuesIn(RandomCases({Matcher::kOptimal, Matcher::kVoc})),
                         RandomCaseName);

// The random sets of the property tests hold every type (the properties are not vacuous).
TEST(ErrorAnalysisTest, RandomFramesHoldEveryType) {
  for (const Matcher m : {Matcher::kKitti, Matcher::kOptimal}) {
    std::array<int64_t, kNumErrorTypes> n{};
    int64_t fixable = 0, fp = 0;
    for (const RandomCase& rc : RandomCases({m})) {
      EvalOptions o;
      o.matcher = m;
      o.num_threads = 2;
      const ErrorClassification c = ClassifyErrors(Frames(rc), o, rc.kind, Difficulty::kModerate);
      for (size_t k = 0; k < c.classes.size(); ++k) {
        const std::array<int64_t, kNumErrorTypes> ck = c.Count(static_cast<int>(k));
        for (int t = 0; t < kNumErrorTypes; ++t) n[t] += ck[t];
        fp += c.cells[k].at_threshold.fp;
      }
      for (const ClassifiedError& e : c.errors) fixable += e.fixable;
    }
    std::printf(
        "%s: %lld FP; cls %lld loc %lld both %lld dupe %lld bkg %lld missed %lld; %lld "
        "winners\n",
        MatcherName(m), static_cast<long long>(fp), static_cast<long long>(n[kCls]),
        static_cast<long long>(n[kLoc]), static_cast<long long>(n[kBoth]),
        static_cast<long long>(n[kDupe]), static_cast<long long>(n[kBkg]),
        static_cast<long long>(n[kMissed]), static_cast<long long>(fixable));
    for (int t = 0; t < kNumErrorTypes; ++t) EXPECT_GT(n[t], 0) << MatcherName(m) << " " << t;
    EXPECT_GT(fixable, 0);
  }
}

// ---------------------------------------------------------------------------------------------
// TIDE itself (dbolya/tide v1.0.1, run unmodified by scripts/tide_reference_cases.py): 2D boxes,
// classes Car and Pedestrian, positive IoU 0.5, background 0.1, all labels of an image disjoint
// (so every detection is matchable to one label at most and TIDE's COCO-style matching equals
// VOC's, and the optimal matcher's where each label's best-scoring candidate also overlaps it
// most). Compared where the association equals TIDE's (its TPs): every detection's type, the
// winners, the missed labels, and per class the AP and each fix's AP in TIDE's own 101-point
// AP computed from the exact curve of the fixed frames (TIDE's per-class APs, not clamped).

// TIDE's APDataObject.get_ap on a curve: mean over x = k/100 of the precision envelope at the
// first point of recall >= x.
double Tide101(const ClassResult& r) {
  const int64_t n = r.num_valid_labels;
  if (n == 0) return 0.0;
  std::vector<double> precision, recall;
  for (const CurvePoint& p : r.curve) {
    precision.push_back(static_cast<double>(p.tp) / static_cast<double>(p.tp + p.fp));
    recall.push_back(static_cast<double>(p.tp) / static_cast<double>(n));
  }
  for (size_t i = precision.size(); i-- > 1;) {
    if (precision[i] > precision[i - 1]) precision[i - 1] = precision[i];
  }
  double sum = 0.0;
  for (int k = 0; k <= 100; ++k) {
    const double x = k / 100.0;
    const auto it = std::lower_bound(recall.begin(), recall.end(), x);
    if (it != recall.end()) sum += precision[it - recall.begin()];
  }
  return sum / 101.0 * 100.0;
}

struct TideCase {
  std::vector<EvalFrame> frames;
  // Per (image, detection index): TIDE's outcome ("tp", "cls", ...) and whether its fix makes it
  // a TP; per (image, label index): missed.
  std::map<std::pair<int, int>, std::pair<std::string, bool>> det_type;
  std::set<std::pair<int, int>> missed;
  // (class, which) -> TIDE's AP: which is "base", an error type's name, "fp" or "fn".
  std::map<std::pair<std::string, std::string>, double> ap;
};

std::map<int, TideCase> ReadTideCases() {
  std::map<int, TideCase> cases;
  std::ifstream in(TestSourceDir() / "tests/data/tide/tide_reference.csv");
  EXPECT_TRUE(in) << "tests/data/tide/tide_reference.csv";
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> v;
    std::stringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(field);
    const int k = std::stoi(v.at(1));
    TideCase& tc = cases[k];
    if (v[0] == "gt" || v[0] == "det") {
      const size_t image = std::stoul(v.at(2));
      if (tc.frames.size() <= image) tc.frames.resize(image + 1);
      EvalFrame& f = tc.frames[image];
      char id[16];
      std::snprintf(id, sizeof id, "%06zu", image);
      f.id = id;
      const Box2D box{std::stod(v.at(5)), std::stod(v.at(6)), std::stod(v.at(7)),
                      std::stod(v.at(8))};
      const int index = std::stoi(v.at(3));
      if (v[0] == "gt") {
        // gt,case,image,index,class,left,top,right,bottom,missed
        EXPECT_EQ(static_cast<size_t>(index), f.labels.size());
        if (v.at(9) == "1") tc.missed.insert({static_cast<int>(image), index});
        f.labels.push_back(Label(v.at(4), box));
      } else {
        // det,case,image,index,class,left,top,right,bottom,score,type,fixed
        EXPECT_EQ(static_cast<size_t>(index), f.detections.size());
        tc.det_type[{static_cast<int>(image), index}] = {v.at(10), v.at(11) == "1"};
        f.detections.push_back(Det(v.at(4), box, std::stod(v.at(9))));
      }
    } else if (v[0] == "ap") {
      // ap,case,class,which,value
      tc.ap[{v.at(2), v.at(3)}] = std::stod(v.at(4));
    }
  }
  return cases;
}

TEST(ErrorAnalysisTest, AgreesWithTideWhereTheDefinitionsCoincide) {
  const std::map<int, TideCase> cases = ReadTideCases();
  ASSERT_GE(cases.size(), 20u);
  std::map<Matcher, int> compared;
  for (const Matcher m : {Matcher::kVoc, Matcher::kOptimal, Matcher::kKitti}) {
    for (const auto& [k, tc] : cases) {
      EvalOptions o;
      ClassSpec car{"Car", {}, {0.5, 0.5, 0.5, 0.5, 0.5}};
      ClassSpec ped{"Pedestrian", {}, {0.5, 0.5, 0.5, 0.5, 0.5}};
      o.classes = {car, ped};
      o.metrics = {OverlapKind::k2D};
      o.difficulties = {Difficulty::kModerate};
      o.matcher = m;
      o.require_detections = false;
      o.num_threads = 1;
      const ErrorClassification c =
          ClassifyErrors(tc.frames, o, OverlapKind::k2D, Difficulty::kModerate);
      // The association equals TIDE's where the same detections are TPs.
      bool same = true;
      for (const auto& [key, type] : tc.det_type) {
        const bool ours_tp = FindDetection(c, key.first, key.second) == nullptr;
        same &= ours_tp == (type.first == "tp");
      }
      if (!same) {
        EXPECT_NE(m, Matcher::kVoc) << "case " << k << ": VOC's association is TIDE's here";
        continue;
      }
      ++compared[m];
      for (const auto& [key, type] : tc.det_type) {
        const ClassifiedError* e = FindDetection(c, key.first, key.second);
        if (e == nullptr) continue;
        EXPECT_EQ(ErrorTypeName(e->type), type.first)
            << "case " << k << " image " << key.first << " detection " << key.second << " ("
            << MatcherName(m) << ")";
        EXPECT_EQ(e->fixable, type.second) << "case " << k << " detection " << key.second;
      }
      std::set<std::pair<int, int>> missed;
      for (const ClassifiedError& e : c.errors) {
        if (e.type == ErrorType::kMissed) missed.insert({e.frame, e.label});
      }
      EXPECT_EQ(missed, tc.missed) << "case " << k << " (" << MatcherName(m) << ")";
      if (m == Matcher::kKitti) continue;  // the devkit's AP is not TIDE's
      for (int ci = 0; ci < 2; ++ci) {
        const std::string name = c.classes[ci].name;
        EvalOptions one = o;
        one.classes = {c.classes[ci]};
        auto ap = [&](const std::vector<EvalFrame>& fr) {
          return Tide101(Evaluate(fr, one).results.at(0));
        };
        EXPECT_NEAR(ap(tc.frames), tc.ap.at({name, "base"}), 1e-9) << "case " << k << " " << name;
        for (int t = 0; t < kNumErrorTypes; ++t) {
          const ErrorType type = static_cast<ErrorType>(t);
          EXPECT_NEAR(ap(FixErrors(tc.frames, c, ci, {type})),
                      tc.ap.at({name, ErrorTypeName(type)}), 1e-9)
              << "case " << k << " " << name << " " << ErrorTypeName(type) << " (" << MatcherName(m)
              << ")";
        }
        EXPECT_NEAR(ap(FixSpecialError(tc.frames, c, ci, SpecialError::kFalsePositives)),
                    tc.ap.at({name, "fp"}), 1e-9)
            << "case " << k << " " << name;
        EXPECT_NEAR(ap(FixSpecialError(tc.frames, c, ci, SpecialError::kFalseNegatives)),
                    tc.ap.at({name, "fn"}), 1e-9)
            << "case " << k << " " << name;
      }
    }
  }
  EXPECT_EQ(compared[Matcher::kVoc], static_cast<int>(cases.size()));
  EXPECT_GE(compared[Matcher::kOptimal], static_cast<int>(cases.size()) / 2);
  EXPECT_GE(compared[Matcher::kKitti], static_cast<int>(cases.size()) / 2);
  std::printf("TIDE cases: %zu; compared: VOC %d, optimal %d, KITTI %d (types only)\n",
              cases.size(), compared[Matcher::kVoc], compared[Matcher::kOptimal],
              compared[Matcher::kKitti]);
}

// The cost of the analysis on a KITTI-val-sized random set (3769 frames), every cell of Car,
// Pedestrian, Cyclist x 2D, BEV, 3D x Easy, Moderate, Hard, against one Evaluate of the same
// cells. Disabled: run with --gtest_also_run_disabled_tests.
TEST(ErrorAnalysisTest, DISABLED_CostOnAKittiValSizedSet) {
  RandomFramesOptions ro;
  ro.num_frames = 3769;
  ro.seed = 2024;
  ro.score_decimals = 2;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (const Matcher m : {Matcher::kKitti, Matcher::kOptimal}) {
    EvalOptions o;
    o.matcher = m;
    o.num_threads = 1;
    const auto t0 = std::chrono::steady_clock::now();
    const EvalResult r = Evaluate(frames, o);
    const auto t1 = std::chrono::steady_clock::now();
    const std::vector<ErrorAnalysis> a = AnalyzeAllErrors(frames, o);
    const auto t2 = std::chrono::steady_clock::now();
    const double evaluate_s = std::chrono::duration<double>(t1 - t0).count();
    const double analysis_s = std::chrono::duration<double>(t2 - t1).count();
    ASSERT_EQ(a.size(), r.results.size());
    std::printf("%s: Evaluate %.2f s, AnalyzeAllErrors %.2f s (%zu cells, %.1fx)\n", MatcherName(m),
                evaluate_s, analysis_s, a.size(), analysis_s / evaluate_s);
    for (const ErrorAnalysis& x : a) {
      if (x.class_name != "Car" || x.difficulty != Difficulty::kModerate) continue;
      std::printf(
          "  Car %s Moderate: AP_R40 %.2f; dAP cls %.2f loc %.2f both %.2f dupe %.2f bkg "
          "%.2f missed %.2f; FP %.2f FN %.2f; counts %lld %lld %lld %lld %lld %lld\n",
          OverlapKindName(x.kind), x.ap_r40, x.delta_ap_r40[kCls], x.delta_ap_r40[kLoc],
          x.delta_ap_r40[kBoth], x.delta_ap_r40[kDupe], x.delta_ap_r40[kBkg],
          x.delta_ap_r40[kMissed], x.delta_fp_r40, x.delta_fn_r40,
          static_cast<long long>(x.count[kCls]), static_cast<long long>(x.count[kLoc]),
          static_cast<long long>(x.count[kBoth]), static_cast<long long>(x.count[kDupe]),
          static_cast<long long>(x.count[kBkg]), static_cast<long long>(x.count[kMissed]));
    }
  }
}

}  // namespace
}  // namespace stereodet
