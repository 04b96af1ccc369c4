#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <utility>

#include "stereodet/eval/associate_internal.h"
#include "stereodet/eval/bipartite_internal.h"
#include "stereodet/eval/curve_events_internal.h"

namespace stereodet {

Tally TallyAssociation(const EvalFrame& frame, const ClassFrame& cf, const FrameAssociation& a,
                       const StableSelection* selection) {
  Tally t;
  TallyBins(cf, a, MaskSelection(frame, cf, selection), 1, &t);
  return t;
}

BinMasks MaskSelection(const EvalFrame& frame, const ClassFrame& cf,
                       const StableSelection* selection) {
  if (selection != nullptr) return MaskBins(frame, cf, {*selection});
  BinMasks m;
  m.num_labels = cf.num_labels();
  m.num_dets = cf.num_dets();
  m.label.assign(m.num_labels, 1);
  m.det.assign(m.num_dets, 1);
  return m;
}

BinMasks MaskBins(const EvalFrame& frame, const ClassFrame& cf,
                  const std::vector<StableSelection>& selections) {
  BinMasks m;
  const size_t n_s = selections.size();
  m.num_labels = cf.num_labels();
  m.num_dets = cf.num_dets();
  m.pair_needs_det = n_s > 0 && selections.front().conditions != nullptr;
  m.label.resize(n_s * static_cast<size_t>(m.num_labels));
  m.det.resize(n_s * static_cast<size_t>(m.num_dets));
  // Each object read once for all the selections.
  for (int i = 0; i < m.num_labels; ++i) {
    const Object& label = frame.labels[cf.label_object[i]];
    for (size_t s = 0; s < n_s; ++s) {
      m.label[s * m.num_labels + i] = selections[s].KeepsLabel(label) ? 1 : 0;
    }
  }
  for (int j = 0; j < m.num_dets; ++j) {
    const Object& det = frame.detections[cf.det_object[j]];
    for (size_t s = 0; s < n_s; ++s) {
      m.det[s * m.num_dets + j] = selections[s].KeepsDetection(det) ? 1 : 0;
    }
  }
  return m;
}

void TallyBins(const ClassFrame& cf, const FrameAssociation& a, const BinMasks& masks, size_t n_s,
               Tally* out) {
  TallyLabels(cf, a, masks, n_s, out);
  const size_t nd = static_cast<size_t>(cf.num_dets());
  for (size_t j = 0; j < nd; ++j) {
    if (a.det_outcome[j] != Outcome::kFp) continue;
    for (size_t s = 0; s < n_s; ++s) out[s].fp += masks.det[s * nd + j];
  }
}

void TallyLabels(const ClassFrame& cf, const FrameAssociation& a, const BinMasks& masks, size_t n_s,
                 Tally* out) {
  const size_t nl = static_cast<size_t>(cf.num_labels()), nd = static_cast<size_t>(cf.num_dets());
  for (size_t i = 0; i < nl; ++i) {
    if (a.label_outcome[i] == Outcome::kTp) {
      const int j = a.label_det[i];
      const int label = static_cast<int>(i);
      const double weight =
          cf.TpWeight(label, j, cf.edge_affinity.empty() ? -1 : cf.FindEdge(label, j));
      for (size_t s = 0; s < n_s; ++s) {
        if (masks.label[s * nl + i] && (!masks.pair_needs_det || masks.det[s * nd + j])) {
          ++out[s].tp;
          out[s].similarity += weight;
        }
      }
    } else if (a.label_outcome[i] == Outcome::kFn) {
      for (size_t s = 0; s < n_s; ++s) out[s].fn += masks.label[s * nl + i];
    }
  }
}

void TallyNoDetections(const ClassFrame& cf, Difficulty difficulty, const BinMasks& masks,
                       size_t n_s, Tally* out) {
  const size_t nl = static_cast<size_t>(cf.num_labels());
  for (size_t i = 0; i < nl; ++i) {
    if (!cf.LabelValid(static_cast<int>(i), difficulty)) continue;
    for (size_t s = 0; s < n_s; ++s) out[s].fn += masks.label[s * nl + i];
  }
}

namespace {

// AOS of the optimal matcher: above this many distinct scores in one connected component, the
// similarity is recomputed at kAosSamples of them only (see FrameEventsFromAssociations).
constexpr size_t kMaxExactAosScores = 256;
constexpr size_t kAosSamples = 64;

// Memory reused by one thread from call to call of FrameEventsFromAssociations: it runs once per
// frame, class, difficulty and cell, mostly on frames of a few objects, where allocating its lists
// afresh cost as much as the associations.
struct EventScratch {
  std::vector<uint8_t> role, any_edge;
  std::vector<int32_t> order;
  std::vector<std::pair<double, bool>> scores, sampled;
  std::vector<Tally> prev, cur;
  FrameAssociation a;
};

EventScratch& EventMemory() {
  thread_local EventScratch scratch;
  return scratch;
}

// AssociationEvents for each of the first `n_s` selections of `masks` from the association at each
// distinct score where one can change (below), appended to events[s] (an array of n_s lists), each
// selection's FN with no detection taken added to base_fn[s]; with `similarity_only` only the
// similarity changes are emitted.
void FrameEventsFromAssociations(const FrameAssociator& associator, const ClassFrame& cf,
                                 Difficulty difficulty, const BinMasks& masks, size_t n_s,
                                 bool similarity_only, bool with_aos,
                                 std::vector<CurveEvent>* events, int64_t* base_fn) {
  EventScratch& scratch = EventMemory();
  std::vector<Tally>& prev = scratch.prev;
  std::vector<Tally>& cur = scratch.cur;
  prev.assign(n_s, Tally{});
  TallyNoDetections(cf, difficulty, masks, n_s, prev.data());  // above every score
  for (size_t s = 0; s < n_s; ++s) base_fn[s] += prev[s].fn;
  if (cf.num_dets() == 0) return;  // no score: no event
  // What each detection can do when it enters: kPairs, change a pair or excuse a label (it is of
  // the class, with an edge to a valid label); kAloneFp, nothing but count as a FP (of the class,
  // high enough for the difficulty, overlapping no label at all, outside DontCare); kNothing, the
  // rest (another class's, or one that is ignored or excused whatever the threshold). Only scores
  // with a kPairs detection need the association again, and only those with a kAloneFp one change
  // a count otherwise: a detection that is not kPairs changes no pair of the optimal or VOC
  // association and excuses no label (the optimal matcher's graph holds valid labels only; VOC
  // pairs it with an ignored label or nothing), and its own outcome is the same at every threshold.
  enum Role : uint8_t { kNothing = 0, kPairs = 1, kAloneFp = 2 };
  std::vector<uint8_t>& role = scratch.role;
  role.assign(cf.num_dets(), kNothing);
  std::vector<uint8_t>& any_edge = scratch.any_edge;
  any_edge.assign(cf.num_dets(), 0);
  for (int i = 0; i < cf.num_labels(); ++i) {
    const bool valid = cf.LabelValid(i, difficulty);
    for (int e = cf.edge_begin[i]; e < cf.edge_begin[i + 1]; ++e) {
      const int32_t j = cf.edge_det[e];
      any_edge[j] = 1;
      if (valid && cf.det_is_class[j]) role[j] = kPairs;
    }
  }
  // (det_state 0: of the class and high enough for the difficulty, derived once per frame.)
  const bool has_states =
      cf.det_state.size() == static_cast<size_t>(cf.num_dets()) * kNumDifficulties;
  const double min_height = KittiDifficultyLimits(difficulty).min_height_px;
  for (int j = 0; j < cf.num_dets(); ++j) {
    if (any_edge[j] || cf.det_dontcare[j]) continue;
    const bool counts = has_states
                            ? cf.det_state[static_cast<size_t>(j) * kNumDifficulties +
                                           static_cast<size_t>(difficulty)] == 0
                            : cf.det_is_class[j] && !(std::trunc(cf.det_height[j]) < min_height);
    if (counts) role[j] = kAloneFp;
  }
  // (The KITTI matcher's greedy is not an optimum: a detection on an ignored label may become a FP
  // when another takes the label, so with it every score is associated and nothing is skipped.)
  const bool exact = associator.matcher() != Matcher::kKitti;
  // Nothing that can change a count (a frame with only other classes' detections, or ignored
  // ones; about a third of the class frames of a KITTI-like set): no event.
  const uint8_t needed = similarity_only ? kPairs : kPairs | kAloneFp;
  if (exact &&
      std::none_of(role.begin(), role.end(), [&](uint8_t r) { return (r & needed) != 0; })) {
    return;
  }
  std::vector<int32_t>& order = scratch.order;
  order.resize(cf.num_dets());
  std::iota(order.begin(), order.end(), 0);
  // (Any order among equal scores: they enter together.)
  StableSortSmall(order.begin(), order.end(),
                  [&](int a, int b) { return cf.det_score[a] > cf.det_score[b]; });
  // The distinct scores that change something, each with whether it needs the association.
  std::vector<std::pair<double, bool>>& scores = scratch.scores;
  scores.clear();
  for (size_t k = 0; k < order.size();) {
    const double score = cf.det_score[order[k]];
    bool relevant = !exact, alone_fp = false;
    for (; k < order.size() && cf.det_score[order[k]] == score; ++k) {
      relevant |= role[order[k]] == kPairs;
      alone_fp |= role[order[k]] == kAloneFp;
    }
    if (relevant || (alone_fp && !similarity_only)) scores.emplace_back(score, relevant);
  }
  if (similarity_only && scores.size() > kMaxExactAosScores) {
    // A huge component (thousands of overlapping detections): bound the cost to kAosSamples
    // associations, evenly spaced over its scores, the lowest included; the similarity is held
    // between them (documented approximation; the counts are exact, they come from elsewhere).
    std::vector<std::pair<double, bool>>& sampled = scratch.sampled;
    sampled.clear();
    for (size_t s = 1; s <= kAosSamples; ++s)
      sampled.push_back(scores[s * scores.size() / kAosSamples - 1]);
    scores.swap(sampled);
  }
  // Every association in the memory of the one before.
  FrameAssociation& a = scratch.a;
  cur.resize(n_s);
  size_t next = 0;  // into `order`: the first detection not yet entered
  for (const auto& [score, relevant] : scores) {
    // The detections entering at this score (order is by descending score).
    const size_t first = next;
    while (next < order.size() && cf.det_score[order[next]] >= score) ++next;
    if (relevant) {
      std::fill(cur.begin(), cur.end(), Tally{});
      a = associator.At(score, std::move(a));
      TallyBins(cf, a, masks, n_s, cur.data());
    } else {
      for (size_t s = 0; s < n_s; ++s) {
        cur[s] = prev[s];
        for (size_t k = first; k < next; ++k) {
          const int j = order[k];
          if (role[j] == kAloneFp && masks.Bin(s).KeepsDetection(j)) ++cur[s].fp;
        }
      }
    }
    for (size_t s = 0; s < n_s; ++s) {
      // Without AOS the similarity takes no part (it must not add curve points).
      const double similarity = with_aos ? cur[s].similarity - prev[s].similarity : 0.0;
      const int32_t tp = similarity_only ? 0 : static_cast<int32_t>(cur[s].tp - prev[s].tp);
      const int32_t fp = similarity_only ? 0 : static_cast<int32_t>(cur[s].fp - prev[s].fp);
      const int32_t fn = similarity_only ? 0 : static_cast<int32_t>(cur[s].fn - prev[s].fn);
      if (tp != 0 || fp != 0 || fn != 0 || similarity != 0.0) {
        events[s].push_back(CurveEvent{score, tp, fp, fn, similarity});
      }
      prev[s] = cur[s];
    }
  }
}

// FrameEventsFromAssociations into FrameCurveEvents, out[0].events starting as `append_to`.
std::vector<FrameCurveEvents> FrameEventsOf(Matcher matcher, const ClassFrame& cf,
                                            Difficulty difficulty, const BinMasks& masks,
                                            size_t n_s, bool similarity_only, bool with_aos,
                                            std::vector<CurveEvent> append_to) {
  std::vector<std::vector<CurveEvent>> events(n_s);
  std::vector<int64_t> base_fn(n_s, 0);
  if (n_s > 0) events[0] = std::move(append_to);
  FrameEventsFromAssociations(FrameAssociator(matcher, cf, difficulty), cf, difficulty, masks, n_s,
                              similarity_only, with_aos, events.data(), base_fn.data());
  std::vector<FrameCurveEvents> out(n_s);
  for (size_t s = 0; s < n_s; ++s) {
    out[s].events = std::move(events[s]);
    out[s].base_fn = base_fn[s];
  }
  return out;
}

// Memory reused by one thread from call to call: OptimalSimilarityEvents runs once per frame,
// class and difficulty, mostly on small frames, where allocating its buffers afresh cost about as
// much as the work (docs/BENCHMARKS.md, issue 10).
struct ComponentScratch {
  DisjointSets sets;
  std::vector<int32_t> det_degree, comp_of_root, local;
  std::vector<uint8_t> single;
  std::vector<ClassFrame> comps;  // the first num_comps hold this call's components
  int num_comps = 0;
  std::vector<std::pair<int32_t, int32_t>> dets;  // SingleLabelSimilarityEvents'
};

ComponentScratch& ComponentMemory() {
  thread_local ComponentScratch scratch;
  return scratch;
}

// The connected components of `cf`'s overlap graph that have an edge, each as a ClassFrame of its
// own (object indices still into the frame's EvalFrame), in scratch->comps[0, num_comps). The
// optimal association decomposes over them, and detections without an edge pair with nothing, so
// the TP pairs of `cf` at any threshold are the union of the components' TP pairs.
//
// A component of one label (the common case) is not copied: `on_label(i)` is called for it instead
// (before this returns; it may use scratch->dets).
template <typename OnLabel>
void EdgeComponents(const ClassFrame& cf, OnLabel on_label, ComponentScratch* scratch) {
  const int nl = cf.num_labels(), nd = cf.num_dets();
  DisjointSets& sets = scratch->sets;
  sets.Reset(nl + nd);
  for (int i = 0; i < nl; ++i) {
    for (int e = cf.edge_begin[i]; e < cf.edge_begin[i + 1]; ++e)
      sets.Union(i, nl + cf.edge_det[e]);
  }
  // Single-label components first: a label whose detections overlap no other label.
  std::vector<int32_t>& det_degree = scratch->det_degree;
  det_degree.assign(nd, 0);
  for (const int32_t j : cf.edge_det) ++det_degree[j];
  std::vector<uint8_t>& single = scratch->single;
  single.assign(nl, 0);
  bool any_multi = false;
  for (int i = 0; i < nl; ++i) {
    if (cf.edge_begin[i + 1] == cf.edge_begin[i]) continue;
    bool alone = true;
    for (int e = cf.edge_begin[i]; e < cf.edge_begin[i + 1]; ++e)
      alone &= det_degree[cf.edge_det[e]] == 1;
    if (alone) {
      single[i] = 1;
      on_label(i);
    } else {
      any_multi = true;
    }
  }
  scratch->num_comps = 0;
  if (!any_multi) return;  // every edge is in a one-label component
  std::vector<int32_t>& comp_of_root = scratch->comp_of_root;
  std::vector<int32_t>& local = scratch->local;
  comp_of_root.assign(nl + nd, -1);
  local.assign(nl + nd, -1);
  std::vector<ClassFrame>& comps = scratch->comps;
  auto comp = [&](int x) -> ClassFrame& {
    const int r = sets.Find(x);
    if (comp_of_root[r] < 0) {
      comp_of_root[r] = scratch->num_comps++;
      if (static_cast<int>(comps.size()) < scratch->num_comps) comps.emplace_back();
      ClassFrame& c = comps[comp_of_root[r]];
      c.Clear();
      c.min_overlap = cf.min_overlap;
    }
    return comps[comp_of_root[r]];
  };
  for (int i = 0; i < nl; ++i) {
    if (cf.edge_begin[i + 1] == cf.edge_begin[i] || single[i]) continue;
    ClassFrame& c = comp(i);
    local[i] = c.num_labels();
    c.label_object.push_back(cf.label_object[i]);
    c.label_neighbour.push_back(cf.label_neighbour[i]);
    c.label_difficulty.push_back(cf.label_difficulty[i]);
    c.label_alpha.push_back(cf.label_alpha[i]);
  }
  for (int j = 0; j < nd; ++j) {
    if (comp_of_root[sets.Find(nl + j)] < 0) continue;  // no edge, or in a single-edge component
    ClassFrame& c = comp(nl + j);
    local[nl + j] = c.num_dets();
    c.det_object.push_back(cf.det_object[j]);
    c.det_is_class.push_back(cf.det_is_class[j]);
    c.det_height.push_back(cf.det_height[j]);
    c.det_score.push_back(cf.det_score[j]);
    c.det_alpha.push_back(cf.det_alpha[j]);
    c.det_dontcare.push_back(cf.det_dontcare[j]);
  }
  for (int k = 0; k < scratch->num_comps; ++k) comps[k].edge_begin.push_back(0);
  for (int i = 0; i < nl; ++i) {  // labels in order, so each component's CSR is built in order
    if (local[i] < 0) continue;
    ClassFrame& c = comps[comp_of_root[sets.Find(i)]];
    for (int e = cf.edge_begin[i]; e < cf.edge_begin[i + 1]; ++e) {
      c.edge_det.push_back(local[nl + cf.edge_det[e]]);
      c.edge_overlap.push_back(cf.edge_overlap[e]);
      if (!cf.edge_affinity.empty()) c.edge_affinity.push_back(cf.edge_affinity[e]);
    }
    c.edge_begin.push_back(static_cast<int32_t>(c.edge_det.size()));
  }
}

// The similarity events of a component made of one label and the detections overlapping only it.
// The optimal association pairs the label, if valid, with its best present valid detection: the
// largest (not inside DontCare, ClassFrame::EdgeWeight), the lowest index among equals
// (OptimalAssociate makes the same choice for a one-label component). So the partner changes only
// when a better detection arrives.
void SingleLabelSimilarityEvents(const ClassFrame& cf, int label, Difficulty difficulty,
                                 std::vector<std::pair<int32_t, int32_t>>* dets_memory,
                                 std::vector<CurveEvent>* events) {
  if (!cf.LabelValid(label, difficulty)) return;
  const double min_height = KittiDifficultyLimits(difficulty).min_height_px;
  std::vector<std::pair<int32_t, int32_t>>& dets = *dets_memory;  // (detection, edge), valid ones
  dets.clear();
  for (int e = cf.edge_begin[label]; e < cf.edge_begin[label + 1]; ++e) {
    const int j = cf.edge_det[e];
    if (cf.det_is_class[j] && std::trunc(cf.det_height[j]) >= min_height) dets.emplace_back(j, e);
  }
  StableSortSmall(dets.begin(), dets.end(), [&](const auto& a, const auto& b) {
    return cf.det_score[a.first] > cf.det_score[b.first];
  });
  auto better = [&](const std::pair<int32_t, int32_t>& a, const std::pair<int32_t, int32_t>& b) {
    const int ka = cf.det_dontcare[a.first] ? 0 : 1, kb = cf.det_dontcare[b.first] ? 0 : 1;
    if (ka != kb) return ka > kb;
    const double wa = cf.EdgeWeight(a.second), wb = cf.EdgeWeight(b.second);
    if (wa != wb) return wa > wb;
    return a.first < b.first;
  };
  int best = -1;
  double similarity = 0.0;
  for (size_t k = 0; k < dets.size();) {
    const double score = cf.det_score[dets[k].first];
    const int before = best;
    for (; k < dets.size() && cf.det_score[dets[k].first] == score; ++k) {
      if (best < 0 || better(dets[k], dets[best])) best = static_cast<int>(k);
    }
    if (best == before) continue;
    const double now = cf.TpWeight(label, dets[best].first, dets[best].second);
    CurveEvent ev;
    ev.score = score;
    ev.similarity = now - similarity;
    similarity = now;
    if (ev.similarity != 0.0) events->push_back(ev);
  }
}

}  // namespace

FrameCurveEvents AssociationEvents(Matcher matcher, const EvalFrame& frame, const ClassFrame& cf,
                                   Difficulty difficulty, const StableSelection* selection,
                                   bool with_aos, std::vector<CurveEvent> append_to) {
  return std::move(FrameEventsOf(matcher, cf, difficulty, MaskSelection(frame, cf, selection), 1,
                                 false, with_aos, std::move(append_to))
                       .front());
}

std::vector<FrameCurveEvents> AssociationEvents(Matcher matcher, const ClassFrame& cf,
                                                Difficulty difficulty, const BinMasks& masks,
                                                size_t num_selections, bool with_aos) {
  return FrameEventsOf(matcher, cf, difficulty, masks, num_selections, false, with_aos, {});
}

void AppendAssociationEvents(const FrameAssociator& associator, const ClassFrame& cf,
                             Difficulty difficulty, const BinMasks& masks, size_t num_selections,
                             bool with_aos, std::vector<CurveEvent>* events, int64_t* base_fn) {
  FrameEventsFromAssociations(associator, cf, difficulty, masks, num_selections, false, with_aos,
                              events, base_fn);
}

std::vector<CurveEvent> OptimalSimilarityEvents(const EvalFrame& frame, const ClassFrame& cf,
                                                Difficulty difficulty,
                                                std::vector<CurveEvent> append_to) {
  std::vector<CurveEvent> events = std::move(append_to);
  ComponentScratch& scratch = ComponentMemory();
  auto on_label = [&](int label) {
    SingleLabelSimilarityEvents(cf, label, difficulty, &scratch.dets, &events);
  };
  EdgeComponents(cf, on_label, &scratch);
  int64_t base_fn = 0;  // (not needed: the counts come from elsewhere)
  for (int k = 0; k < scratch.num_comps; ++k) {
    const ClassFrame& comp = scratch.comps[k];
    FrameEventsFromAssociations(FrameAssociator(Matcher::kOptimal, comp, difficulty), comp,
                                difficulty, MaskSelection(frame, comp, nullptr), 1, true, true,
                                &events, &base_fn);
  }
  return events;
}

}  // namespace stereodet
