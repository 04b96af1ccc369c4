#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <utility>

#include "stereodet/eval/bipartite_internal.h"
#include "stereodet/eval/optimal_matcher_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

enum DetRole : int8_t { kOut = 0, kValid = 1, kIgnoredDet = 2 };

struct OptimalGraph {
  std::vector<int8_t> role;             // per detection
  std::vector<uint8_t> label_valid;     // per label
  std::vector<uint8_t> det_excusable;   // valid detection overlapping an ignored label or DontCare
  std::vector<uint8_t> det_on_ignored;  // valid detection overlapping an ignored label
  DetAdjacency adj;                     // detection -> valid labels, overlap >= tau
  std::vector<double> adj_overlap;      // parallel to adj.labels: ClassFrame::EdgeWeight
  std::vector<int32_t> fill;            // scratch of BuildGraph
};

// Memory reused by one thread from call to call. An evaluation runs these functions once per
// frame, class, difficulty (and, for the association, per threshold); most frames are small, so
// allocating every buffer afresh cost more than the matching itself (half the optimal matcher's
// profile was malloc/free before this).
struct ThreadScratch {
  OptimalGraph graph;
  std::vector<int32_t> order;
  IncrementalMatching all, unexcused, labels;
  std::vector<uint8_t> label_excused, present;
  DisjointSets sets;
  std::vector<int32_t> comp_begin, members, local, cl, cd, fill, match;
  std::vector<WeightedEdge> edges;
  // Which BuildGraph made `graph`: a number unique over all threads (OptimalAssociator's check).
  uint64_t graph_generation = 0;
};

ThreadScratch& Scratch() {
  thread_local ThreadScratch scratch;
  return scratch;
}

// Fills *g for `f` at `difficulty`, reusing g's memory (see ThreadScratch).
void BuildGraph(const ClassFrame& f, Difficulty difficulty, OptimalGraph* g) {
  static std::atomic<uint64_t> generations{0};
  Scratch().graph_generation = ++generations;
  const double min_height = KittiDifficultyLimits(difficulty).min_height_px;
  g->role.resize(f.num_dets());
  for (int j = 0; j < f.num_dets(); ++j) {
    if (!f.det_is_class[j])
      g->role[j] = kOut;
    else
      g->role[j] = std::trunc(f.det_height[j]) < min_height ? kIgnoredDet : kValid;
  }
  g->label_valid.resize(f.num_labels());
  for (int i = 0; i < f.num_labels(); ++i) g->label_valid[i] = f.LabelValid(i, difficulty) ? 1 : 0;
  g->det_excusable.assign(f.det_dontcare.begin(), f.det_dontcare.end());
  g->det_on_ignored.assign(f.num_dets(), 0);
  // Transpose the label-major edges into detection-major lists of valid labels.
  std::vector<int32_t>& count = g->adj.begin;
  count.assign(f.num_dets() + 1, 0);
  for (int i = 0; i < f.num_labels(); ++i) {
    for (int e = f.edge_begin[i]; e < f.edge_begin[i + 1]; ++e) {
      const int j = f.edge_det[e];
      if (g->role[j] == kOut) continue;
      if (g->label_valid[i])
        ++count[j + 1];
      else if (g->role[j] == kValid)
        g->det_excusable[j] = g->det_on_ignored[j] = 1;
    }
  }
  std::partial_sum(count.begin(), count.end(), count.begin());
  g->adj.num_labels = f.num_labels();
  g->adj.labels.resize(count.back());
  g->adj_overlap.resize(count.back());
  g->fill.assign(count.begin(), count.end() - 1);
  for (int i = 0; i < f.num_labels(); ++i) {
    if (!g->label_valid[i]) continue;
    for (int e = f.edge_begin[i]; e < f.edge_begin[i + 1]; ++e) {
      const int j = f.edge_det[e];
      if (g->role[j] == kOut) continue;
      g->adj.labels[g->fill[j]] = i;
      g->adj_overlap[g->fill[j]++] = f.EdgeWeight(e);
    }
  }
}

// Detections of the class in descending score (file order among ties), into *order.
void ByDescendingScore(const ClassFrame& f, const std::vector<int8_t>& role,
                       std::vector<int32_t>* order) {
  order->clear();
  for (int j = 0; j < f.num_dets(); ++j) {
    if (role[j] != kOut) order->push_back(j);
  }
  StableSortSmall(order->begin(), order->end(),
                  [&](int a, int b) { return f.det_score[a] > f.det_score[b]; });
}

// The maximum-weight association of each connected component of the overlap graph at the
// threshold (present = detections taking part), written into *assoc's TP pairs.
void MatchComponents(const ClassFrame& f, const OptimalGraph& g,
                     const std::vector<uint8_t>& present, const std::vector<uint8_t>& label_excused,
                     ThreadScratch* scratch, FrameAssociation* assoc);

}  // namespace

int CountValidLabels(const ClassFrame& f, Difficulty difficulty) {
  int n = 0;
  for (int i = 0; i < f.num_labels(); ++i) n += f.LabelValid(i, difficulty) ? 1 : 0;
  return n;
}

namespace {

// OptimalFrameEvents' events of `f`, whose graph `g` (scratch.graph) is built, appended to *events.
void AppendFrameEvents(const ClassFrame& f, const OptimalGraph& g, ThreadScratch& scratch,
                       std::vector<CurveEvent>* events) {
  ByDescendingScore(f, g.role, &scratch.order);
  if (g.adj.labels.empty()) {
    // No detection overlaps a valid label (a class absent from the frame, or all boxes apart):
    // nothing is ever matched or excused by a match, so each valid detection that is not
    // excusable is a FP, and the rest make no event; no matchings to keep.
    for (const int j : scratch.order) {
      if (g.role[j] != kValid || g.det_excusable[j]) continue;
      CurveEvent ev;
      ev.score = f.det_score[j];
      ev.fp = 1;
      events->push_back(ev);
    }
    return;
  }
  // Usually nothing is excused (no valid detection on an ignored label or DontCare, no ignored
  // detection on a valid label); then the FP and FN matchings are the TP matching itself.
  bool any_excusable = false, any_label_excuse = false;
  for (int j = 0; j < f.num_dets(); ++j) {
    any_excusable |= g.role[j] == kValid && g.det_excusable[j];
    any_label_excuse |= g.role[j] == kIgnoredDet && g.adj.begin[j + 1] > g.adj.begin[j];
  }
  IncrementalMatching& all = scratch.all;  // TP(t)
  all.Reset(&g.adj);
  IncrementalMatching* unexcused = nullptr;  // covers the most unexcusable detections: FP(t)
  IncrementalMatching* labels = nullptr;     // covers the most unexcused labels: FN(t)
  if (any_excusable) (unexcused = &scratch.unexcused)->Reset(&g.adj);
  if (any_label_excuse) (labels = &scratch.labels)->Reset(&g.adj);
  std::vector<uint8_t>& label_excused = scratch.label_excused;
  label_excused.assign(f.num_labels(), 0);
  for (const int j : scratch.order) {
    CurveEvent ev;
    ev.score = f.det_score[j];
    if (g.role[j] == kValid) {
      const bool matched = all.AddDet(j);
      if (matched) ++ev.tp;
      if (unexcused) {
        if (!g.det_excusable[j] && !unexcused->AddDet(j)) ++ev.fp;
      } else if (!matched) {
        ++ev.fp;
      }
      if (labels) {
        if (labels->AddDet(j)) --ev.fn;
      } else if (matched) {
        --ev.fn;
      }
    } else if (labels) {
      // An ignored detection excuses the labels it overlaps from now on: they leave the FN count,
      // and the matching of the remaining labels is repaired by one augmenting search.
      for (int k = g.adj.begin[j]; k < g.adj.begin[j + 1]; ++k) {
        const int i = g.adj.labels[k];
        if (label_excused[i]) continue;
        label_excused[i] = 1;
        ev.fn += -1 - labels->RemoveLabel(i);
      }
    }
    if (ev.tp != 0 || ev.fp != 0 || ev.fn != 0) events->push_back(ev);
  }
}

// OptimalAssociate of `f`, whose graph `g` (scratch.graph) is built.
FrameAssociation AssociateOnGraph(const ClassFrame& f, const OptimalGraph& g, double threshold,
                                  ThreadScratch& scratch, FrameAssociation reuse) {
  const int nl = f.num_labels();
  const int nd = f.num_dets();
  FrameAssociation a = std::move(reuse);
  a.label_outcome.assign(nl, Outcome::kIgnored);
  a.label_det.assign(nl, -1);
  a.det_outcome.assign(nd, Outcome::kNone);
  a.det_label.assign(nd, -1);

  std::vector<uint8_t>& present = scratch.present;
  std::vector<uint8_t>& label_excused = scratch.label_excused;
  present.assign(nd, 0);
  label_excused.assign(nl, 0);
  for (int j = 0; j < nd; ++j) {
    present[j] = g.role[j] != kOut && f.det_score[j] >= threshold;
    if (present[j] && g.role[j] == kIgnoredDet) {
      for (int k = g.adj.begin[j]; k < g.adj.begin[j + 1]; ++k) label_excused[g.adj.labels[k]] = 1;
    }
  }

  // No valid label overlaps a detection of the class (the usual case for a class absent from the
  // frame): nothing to match, only the outcomes below.
  if (!g.adj.labels.empty()) MatchComponents(f, g, present, label_excused, &scratch, &a);
  for (int i = 0; i < nl; ++i) {
    if (g.label_valid[i] && a.label_outcome[i] != Outcome::kTp) {
      a.label_outcome[i] = label_excused[i] ? Outcome::kIgnored : Outcome::kFn;
    }
  }
  for (int j = 0; j < nd; ++j) {
    if (!present[j] || a.det_outcome[j] == Outcome::kTp) continue;
    if (g.role[j] == kIgnoredDet || g.det_on_ignored[j])
      a.det_outcome[j] = Outcome::kIgnored;
    else if (g.det_excusable[j])
      a.det_outcome[j] = Outcome::kDontCare;
    else
      a.det_outcome[j] = Outcome::kFp;
  }
  return a;
}

}  // namespace

std::vector<CurveEvent> OptimalFrameEvents(const ClassFrame& f, Difficulty difficulty,
                                           std::vector<CurveEvent> append_to) {
  std::vector<CurveEvent> out = std::move(append_to);
  if (f.num_dets() == 0) return out;  // no events: the valid labels are all FN at every threshold
  ThreadScratch& scratch = Scratch();
  BuildGraph(f, difficulty, &scratch.graph);
  AppendFrameEvents(f, scratch.graph, scratch, &out);
  return out;
}

FrameAssociation OptimalAssociate(const ClassFrame& f, Difficulty difficulty, double threshold,
                                  FrameAssociation reuse) {
  ThreadScratch& scratch = Scratch();
  BuildGraph(f, difficulty, &scratch.graph);
  return AssociateOnGraph(f, scratch.graph, threshold, scratch, std::move(reuse));
}

OptimalAssociator::OptimalAssociator(const ClassFrame& frame, Difficulty difficulty)
    : frame_(frame) {
  ThreadScratch& scratch = Scratch();
  BuildGraph(frame, difficulty, &scratch.graph);
  graph_generation_ = scratch.graph_generation;
}

void OptimalAssociator::CheckGraph() const {
  STEREODET_CHECK(Scratch().graph_generation == graph_generation_)
      << "OptimalAssociator used after another optimal-matcher call on its thread, or on another "
         "thread";
}

FrameAssociation OptimalAssociator::At(double threshold, FrameAssociation reuse) const {
  CheckGraph();
  ThreadScratch& scratch = Scratch();
  return AssociateOnGraph(frame_, scratch.graph, threshold, scratch, std::move(reuse));
}

void OptimalAssociator::AppendFrameEvents(std::vector<CurveEvent>* events) const {
  CheckGraph();
  ThreadScratch& scratch = Scratch();
  if (frame_.num_dets() > 0) stereodet::AppendFrameEvents(frame_, scratch.graph, scratch, events);
}

namespace {

void MatchComponents(const ClassFrame& f, const OptimalGraph& g,
                     const std::vector<uint8_t>& present, const std::vector<uint8_t>& label_excused,
                     ThreadScratch* scratch_ptr, FrameAssociation* assoc) {
  ThreadScratch& scratch = *scratch_ptr;
  FrameAssociation& a = *assoc;
  const int nl = f.num_labels();
  const int nd = f.num_dets();
  auto degree = [&](int j) { return g.adj.begin[j + 1] - g.adj.begin[j]; };
  // Usually no present valid detection overlaps two valid labels: then every component is one
  // label and the detections overlapping it, and its maximum-weight association is the label's
  // best edge, found in one pass in ascending detection order, without the union-find below.
  // Within such a component K^2 and the label's excuse are the same for every edge, so the best is
  // by (not excusable, overlap), the lowest detection index among equals: the general path's
  // one-label choice.
  bool stars = true;
  for (int j = 0; j < nd && stars; ++j) {
    stars = !(present[j] && g.role[j] == kValid && degree(j) > 1);
  }
  if (stars) {
    std::vector<int32_t>& best = scratch.match;  // per label: its best detection, or -1
    best.assign(nl, -1);
    for (int j = 0; j < nd; ++j) {
      if (!present[j] || g.role[j] != kValid || degree(j) == 0) continue;
      const int k = g.adj.begin[j];
      int32_t& b = best[g.adj.labels[k]];
      if (b >= 0) {
        const bool covers = !g.det_excusable[j], b_covers = !g.det_excusable[b];
        if (covers != b_covers ? !covers : !(g.adj_overlap[k] > g.adj_overlap[g.adj.begin[b]]))
          continue;
      }
      b = j;
    }
    for (int i = 0; i < nl; ++i) {
      const int j = best[i];
      if (j < 0) continue;
      a.label_outcome[i] = Outcome::kTp;
      a.label_det[i] = j;
      a.det_outcome[j] = Outcome::kTp;
      a.det_label[j] = i;
    }
    return;
  }
  // Connected components of (valid labels) + (present valid detections), union-find.
  DisjointSets& sets = scratch.sets;
  sets.Reset(nl + nd);
  for (int j = 0; j < nd; ++j) {
    if (!present[j] || g.role[j] != kValid) continue;
    for (int k = g.adj.begin[j]; k < g.adj.begin[j + 1]; ++k) sets.Union(g.adj.labels[k], nl + j);
  }
  // Group the vertices by component (counting sort on the root) into one flat array.
  std::vector<int32_t>& comp_begin = scratch.comp_begin;
  std::vector<int32_t>& members = scratch.members;
  comp_begin.assign(nl + nd + 1, 0);
  members.resize(nl + nd);
  auto in_graph = [&](int x) {
    return x < nl ? g.label_valid[x] != 0 : (present[x - nl] && g.role[x - nl] == kValid);
  };
  for (int x = 0; x < nl + nd; ++x) {
    if (in_graph(x)) ++comp_begin[sets.Find(x) + 1];
  }
  for (int r = 0; r < nl + nd; ++r) comp_begin[r + 1] += comp_begin[r];
  {
    std::vector<int32_t>& fill = scratch.fill;
    fill.assign(comp_begin.begin(), comp_begin.end() - 1);
    for (int x = 0; x < nl + nd; ++x) {
      if (in_graph(x)) members[fill[sets.Find(x)]++] = x;
    }
  }
  std::vector<int32_t>& local = scratch.local;
  std::vector<int32_t>& cl = scratch.cl;
  std::vector<int32_t>& cd = scratch.cd;
  std::vector<WeightedEdge>& edges = scratch.edges;
  local.assign(nl + nd, -1);
  for (int root = 0; root < nl + nd; ++root) {
    if (comp_begin[root + 1] - comp_begin[root] < 2) continue;  // an isolated vertex
    cl.clear();
    cd.clear();
    for (int k = comp_begin[root]; k < comp_begin[root + 1]; ++k) {
      const int x = members[k];
      if (x < nl) {
        local[x] = static_cast<int32_t>(cl.size());
        cl.push_back(x);
      } else {
        local[x] = static_cast<int32_t>(cd.size());
        cd.push_back(x - nl);
      }
    }
    // Weight of a pair: K^2 (one TP) + K (the detection could not be excused otherwise) + 1 (nor
    // the label), then the overlap. With K above any count in the component the integer part orders
    // matchings by (TPs, unexcusable detections covered, unexcused labels covered) exactly.
    const int64_t big_k = static_cast<int64_t>(std::max(cl.size(), cd.size())) + 1;
    edges.clear();
    for (const int j : cd) {
      for (int k = g.adj.begin[j]; k < g.adj.begin[j + 1]; ++k) {
        const int i = g.adj.labels[k];
        WeightedEdge e;
        e.label = local[i];
        e.det = local[nl + j];
        e.weight.major =
            big_k * big_k + (g.det_excusable[j] ? 0 : big_k) + (label_excused[i] ? 0 : 1);
        e.weight.minor = g.adj_overlap[k];
        edges.push_back(e);
      }
    }
    std::vector<int32_t>& match = scratch.match;
    if (cl.size() == 1 && cd.size() == 1) {
      match.assign(1, 0);  // one edge: take it
    } else if (cl.size() == 1) {
      // One label: its best edge, the first (lowest detection index) among equal weights. The AOS
      // curve (evaluator.cc, SingleLabelSimilarityEvents) relies on this exact choice.
      size_t best = 0;
      for (size_t k = 1; k < edges.size(); ++k) {
        const LexWeight& w = edges[k].weight;
        const LexWeight& b = edges[best].weight;
        if (w.major > b.major || (w.major == b.major && w.minor > b.minor)) best = k;
      }
      match.assign(1, edges[best].det);
    } else {
      match = MaxWeightAssignment(static_cast<int>(cl.size()), static_cast<int>(cd.size()), edges);
    }
    for (size_t k = 0; k < cl.size(); ++k) {
      if (match[k] < 0) continue;
      const int i = cl[k], j = cd[match[k]];
      a.label_outcome[i] = Outcome::kTp;
      a.label_det[i] = j;
      a.det_outcome[j] = Outcome::kTp;
      a.det_label[j] = i;
    }
  }
}

}  // namespace

}  // namespace stereodet
