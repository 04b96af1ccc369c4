// Per-detection records (EvalOptions::keep_records): the outcome of every detection and label, and
// that the records re-sum to the table (operating-point counts and Brier scores) exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "stereodet/eval/evaluator.h"
#include "stereodet/eval/random_frames.h"
#include "stereodet/eval/test_objects.h"

namespace stereodet {
namespace {

using testing_objects::Det;
using testing_objects::Label;

EvalOptions CarModerate2D(Matcher matcher) {
  EvalOptions o;
  o.classes = {KittiClassSpec("Car")};
  o.metrics = {OverlapKind::k2D};
  o.difficulties = {Difficulty::kModerate};
  o.matcher = matcher;
  o.keep_records = true;
  o.num_threads = 2;
  return o;
}

class RecordsByMatcherTest : public ::testing::TestWithParam<Matcher> {};

// One frame where every outcome occurs, the same in all three matchers.
TEST_P(RecordsByMatcherTest, EveryOutcomeOfAHandMadeFrame) {
  EvalFrame f;
  f.id = "000007";
  f.labels.push_back(Label("Car", {100, 100, 200, 200}));  // 0: found
  f.labels.push_back(Label("Van", {300, 100, 400, 200}));  // 1: neighbour class
  f.labels.push_back(
      Label("DontCare", {500, 100, 600, 200}));             // 2: not a row (no class frame label)
  f.labels.push_back(Label("Car", {900, 100, 1000, 200}));  // 3: missed
  f.detections.push_back(Det("Car", {700, 100, 800, 200}, 0.6));   // 0: nothing there: FP
  f.detections.push_back(Det("Car", {100, 100, 200, 200}, 0.9));   // 1: on label 0: TP, IoU 1
  f.detections.push_back(Det("Car", {300, 100, 400, 200}, 0.8));   // 2: on the Van: ignored
  f.detections.push_back(Det("Car", {510, 110, 590, 190}, 0.7));   // 3: inside DontCare
  f.detections.push_back(Det("Car", {950, 100, 1000, 200}, 0.5));  // 4: IoU 0.5 with 3: FP
  const EvalResult result = Evaluate({f}, CarModerate2D(GetParam()));
  ASSERT_EQ(result.results.size(), 1u);
  const std::vector<MatchRecord>& rec = result.results[0].records;
  // Detections in file order, then the labels without a detection (1: Van, 3: missed Car).
  ASSERT_EQ(rec.size(), 7u);
  const Outcome want[] = {Outcome::kFp, Outcome::kTp,      Outcome::kIgnored, Outcome::kDontCare,
                          Outcome::kFp, Outcome::kIgnored, Outcome::kFn};
  const int want_det[] = {0, 1, 2, 3, 4, -1, -1};
  const int want_label[] = {-1, 0, -1, -1, -1, 1, 3};
  for (size_t k = 0; k < rec.size(); ++k) {
    EXPECT_EQ(rec[k].frame, 0) << k;
    EXPECT_EQ(rec[k].outcome, want[k]) << "row " << k << ": " << OutcomeName(rec[k].outcome);
    EXPECT_EQ(rec[k].detection, want_det[k]) << k;
    EXPECT_EQ(rec[k].label, want_label[k]) << k;
  }
  EXPECT_TRUE(rec[1].label_valid);
  EXPECT_FALSE(rec[5].label_valid);  // the Van
  EXPECT_TRUE(rec[6].label_valid);
  EXPECT_DOUBLE_EQ(rec[1].iou, 1.0);  // the TP pair
  EXPECT_DOUBLE_EQ(rec[0].iou, 0.0);  // overlaps nothing
  EXPECT_DOUBLE_EQ(rec[2].iou, 1.0);  // on the Van, exactly
  EXPECT_DOUBLE_EQ(rec[4].iou, 0.5);  // half of label 3: a localisation error, not a ghost
  EXPECT_DOUBLE_EQ(rec[6].iou, 0.5);  // the missed label's best detection
  const OperatingPoint& op = result.results[0].at_threshold;
  EXPECT_EQ(op.tp, 1);
  EXPECT_EQ(op.fp, 2);
  EXPECT_EQ(op.fn, 1);
}

INSTANTIATE_TEST_SUITE_P(AllMatchers, RecordsByMatcherTest,
                         ::testing::Values(Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc),
                         [](const auto& info) { return std::string(MatcherName(info.param)); });

TEST(RecordsTest, NoneWithoutTheOption) {
  RandomFramesOptions ro;
  ro.num_frames = 20;
  EvalOptions o = CarModerate2D(Matcher::kKitti);
  o.keep_records = false;
  const EvalResult r = Evaluate(RandomFrames(ro), o);
  for (const ClassResult& c : r.results) EXPECT_TRUE(c.records.empty());
}

// Property: on random frames, for every matcher, cell and two operating points, the rows give the
// table's TP / FP / FN and its Brier scores over labels and over detections, to the last bit (sums
// taken in the order the evaluator takes them: frames in order, labels by index, detections by
// index).
TEST(RecordsTest, ReSumToTheTableExactly) {
  RandomFramesOptions ro;
  ro.num_frames = 150;
  ro.seed = 11;
  ro.score_decimals = 2;
  const std::vector<EvalFrame> frames = RandomFrames(ro);
  for (const Matcher matcher : {Matcher::kKitti, Matcher::kOptimal, Matcher::kVoc}) {
    for (const double threshold : {-1.0, 0.5}) {
      EvalOptions o;
      o.matcher = matcher;
      o.score_threshold = threshold;
      o.keep_records = true;
      o.num_threads = 2;
      const EvalResult result = Evaluate(frames, o);
      int cells = 0;
      for (const ClassResult& r : result.results) {
        if (!r.evaluated) continue;
        ++cells;
        SCOPED_TRACE(std::string(MatcherName(matcher)) + " " + r.class_name + " " +
                     OverlapKindName(r.metric) + " " + DifficultyName(r.difficulty));
        int64_t tp = 0, fp = 0, fn = 0;
        // frame -> (label index, term) and (detection index, term)
        std::map<int, std::vector<std::pair<int, double>>> label_terms, det_terms;
        for (const MatchRecord& m : r.records) {
          const EvalFrame& f = frames[m.frame];
          if (m.detection >= 0) {
            EXPECT_GE(f.detections[m.detection].score.value(), threshold);
          }
          EXPECT_GE(m.iou, 0.0);
          EXPECT_LE(m.iou, 1.0);
          switch (m.outcome) {
            case Outcome::kTp: {
              ++tp;
              EXPECT_GE(m.iou, r.min_overlap - 1e-4);
              const double s = f.detections[m.detection].score.value();
              label_terms[m.frame].emplace_back(m.label, (1 - s) * (1 - s));
              det_terms[m.frame].emplace_back(m.detection, (s - 1) * (s - 1));
              break;
            }
            case Outcome::kFp: {
              ++fp;
              const double s = f.detections[m.detection].score.value();
              det_terms[m.frame].emplace_back(m.detection, s * s);
              break;
            }
            case Outcome::kFn:
              ++fn;
              EXPECT_EQ(m.detection, -1);
              EXPECT_TRUE(m.label_valid);
              label_terms[m.frame].emplace_back(m.label, 1.0);
              break;
            default:
              EXPECT_TRUE(m.outcome == Outcome::kIgnored || m.outcome == Outcome::kDontCare);
              // A valid label excused by an ignored detection keeps its Brier term (fixed support).
              if (m.detection < 0 && m.label_valid) label_terms[m.frame].emplace_back(m.label, 1.0);
          }
          if (m.outcome == Outcome::kTp) {
            EXPECT_TRUE(m.label_valid);
          }
        }
        EXPECT_EQ(tp, r.at_threshold.tp);
        EXPECT_EQ(fp, r.at_threshold.fp);
        EXPECT_EQ(fn, r.at_threshold.fn);
        auto mean = [](std::map<int, std::vector<std::pair<int, double>>>& terms, int64_t* n) {
          double sum = 0.0;
          *n = 0;
          for (auto& [frame, v] : terms) {
            std::sort(v.begin(), v.end());
            for (const auto& t : v) sum += t.second;
            *n += static_cast<int64_t>(v.size());
          }
          return sum / static_cast<double>(*n);
        };
        int64_t n_labels = 0, n_dets = 0;
        const double brier_labels = mean(label_terms, &n_labels);
        const double brier_dets = mean(det_terms, &n_dets);
        EXPECT_EQ(n_labels, r.brier.num_label_terms);
        EXPECT_EQ(n_labels, r.num_valid_labels);  // the fixed support
        EXPECT_EQ(n_dets, r.brier.num_detection_terms);
        if (n_labels > 0) {
          EXPECT_EQ(brier_labels, r.brier.over_labels);
        }
        if (n_dets > 0) {
          EXPECT_EQ(brier_dets, r.brier.over_detections);
        }
      }
      EXPECT_GE(cells, 20);
    }
  }
}

}  // namespace
}  // namespace stereodet
