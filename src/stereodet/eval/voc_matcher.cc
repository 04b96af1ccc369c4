#include <algorithm>
#include <cmath>
#include <utility>

#include "stereodet/eval/voc_matcher_internal.h"

namespace stereodet {

namespace {

// Runs VOC's greedy over the class's detections with score >= threshold; calls on_det(j, outcome,
// excused_label) for each, in processing order.
template <typename OnDet>
void RunVoc(const ClassFrame& f, Difficulty difficulty, double threshold, OnDet on_det) {
  const double min_height = KittiDifficultyLimits(difficulty).min_height_px;
  // Best label of each detection: the largest overlap (>= tau, as stored; LET kinds: the largest
  // LET-IoU x affinity, ClassFrame::EdgeWeight), lowest label on ties.
  std::vector<int32_t> best_label(f.num_dets(), -1);
  std::vector<double> best_overlap(f.num_dets(), -1.0);
  for (int i = 0; i < f.num_labels(); ++i) {
    for (int e = f.edge_begin[i]; e < f.edge_begin[i + 1]; ++e) {
      const int j = f.edge_det[e];
      if (f.EdgeWeight(e) > best_overlap[j]) {
        best_overlap[j] = f.EdgeWeight(e);
        best_label[j] = i;
      }
    }
  }
  std::vector<int32_t> order;
  for (int j = 0; j < f.num_dets(); ++j) {
    if (f.det_is_class[j] && f.det_score[j] >= threshold) order.push_back(j);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return f.det_score[a] > f.det_score[b]; });
  std::vector<uint8_t> taken(f.num_labels(), 0);
  for (const int j : order) {
    const int i = best_label[j];
    const bool label_valid = i >= 0 && f.LabelValid(i, difficulty);
    if (std::trunc(f.det_height[j]) < min_height) {
      if (label_valid && !taken[i]) {
        taken[i] = 1;
        on_det(j, Outcome::kIgnored, i);
      } else {
        on_det(j, Outcome::kIgnored, -1);
      }
    } else if (i >= 0 && !label_valid) {
      on_det(j, Outcome::kIgnored, -1);
    } else if (i >= 0 && !taken[i]) {
      taken[i] = 1;
      on_det(j, Outcome::kTp, i);
    } else {
      on_det(j, f.det_dontcare[j] ? Outcome::kDontCare : Outcome::kFp, -1);
    }
  }
}

}  // namespace

std::vector<CurveEvent> VocFrameEvents(const ClassFrame& f, Difficulty difficulty,
                                       std::vector<CurveEvent> append_to) {
  std::vector<CurveEvent> out = std::move(append_to);
  std::vector<CurveEvent>* events = &out;
  RunVoc(f, difficulty, -INFINITY, [&](int j, Outcome outcome, int label) {
    CurveEvent ev;
    ev.score = f.det_score[j];
    if (outcome == Outcome::kTp) {
      ev.tp = 1;
      ev.fn = -1;
      // (The edge is looked up only where TpWeight reads it: the LET kinds.)
      ev.similarity = f.TpWeight(label, j, f.edge_affinity.empty() ? -1 : f.FindEdge(label, j));
    } else if (outcome == Outcome::kFp) {
      ev.fp = 1;
    } else if (label >= 0) {
      ev.fn = -1;  // excused by an ignored (too low) detection
    } else {
      return;
    }
    events->push_back(ev);
  });
  return out;
}

FrameAssociation VocAssociate(const ClassFrame& f, Difficulty difficulty, double threshold,
                              FrameAssociation reuse) {
  FrameAssociation a = std::move(reuse);
  a.label_outcome.assign(f.num_labels(), Outcome::kIgnored);
  a.label_det.assign(f.num_labels(), -1);
  a.det_outcome.assign(f.num_dets(), Outcome::kNone);
  a.det_label.assign(f.num_dets(), -1);
  std::vector<uint8_t> excused(f.num_labels(), 0);
  RunVoc(f, difficulty, threshold, [&](int j, Outcome outcome, int label) {
    a.det_outcome[j] = outcome;
    if (outcome == Outcome::kTp) {
      a.det_label[j] = label;
      a.label_outcome[label] = Outcome::kTp;
      a.label_det[label] = j;
    } else if (label >= 0) {
      excused[label] = 1;
    }
  });
  for (int i = 0; i < f.num_labels(); ++i) {
    if (f.LabelValid(i, difficulty) && a.label_outcome[i] != Outcome::kTp && !excused[i]) {
      a.label_outcome[i] = Outcome::kFn;
    }
  }
  return a;
}

}  // namespace stereodet
