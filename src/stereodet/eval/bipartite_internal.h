// Internal to the eval module (used by Evaluate, its tests and benchmarks; not by other modules).
//
// Bipartite matching between labels (left) and detections (right):
//  - DisjointSets: the connected components of an overlap graph;
//  - IncrementalMatching: a maximum-cardinality matching kept maximum while detections are added
//  and
//    labels removed, one augmenting-path search per operation;
//  - MaxWeightAssignment: the Hungarian algorithm (sparse form) on exact lexicographic weights.
#ifndef STEREODET_EVAL_BIPARTITE_INTERNAL_H_
#define STEREODET_EVAL_BIPARTITE_INTERNAL_H_

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace stereodet {

// Adjacency from detections to labels, CSR: detection j's labels are
// labels[begin[j] .. begin[j+1]).
struct DetAdjacency {
  std::vector<int32_t> begin;
  std::vector<int32_t> labels;
  int num_labels = 0;
  int num_dets() const { return static_cast<int>(begin.size()) - 1; }
};

// Sorts [first, last) as std::stable_sort(first, last, less) does, without its temporary buffer:
// insertion sort for the short ranges a frame's detections make (a few to a few dozen; the
// evaluators sort one per frame, class and difficulty, where stable_sort's allocation cost more
// than the sorting), std::stable_sort beyond.
template <typename It, typename Less>
void StableSortSmall(It first, It last, Less less) {
  if (last - first > 32) {
    std::stable_sort(first, last, less);
    return;
  }
  for (It i = first; i != last; ++i) {
    auto value = std::move(*i);
    It j = i;
    for (; j != first && less(value, *(j - 1)); --j) *j = std::move(*(j - 1));
    *j = std::move(value);
  }
}

// Disjoint sets over the vertices 0 .. n-1 (labels and detections of a frame as one range, e.g.
// label i = i and detection j = num_labels + j), with path halving. Union(a, b) links a's root
// under b's, so for a given sequence of unions the roots, and hence the order in which callers meet
// the components, are fixed. Reset keeps the memory (one instance per thread can be reused).
class DisjointSets {
 public:
  DisjointSets() = default;
  explicit DisjointSets(int n) { Reset(n); }

  void Reset(int n) {
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int Find(int x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void Union(int a, int b) {
    const int ra = Find(a), rb = Find(b);
    if (ra != rb) parent_[ra] = rb;
  }

 private:
  std::vector<int32_t> parent_;
};

// A maximum matching of (present labels) x (added detections), kept maximum:
//  - AddDet(j): detection j joins; one augmenting-path search from j. Adding detections in any
//    order keeps the matching maximum after every step (a matched vertex never becomes unmatched
//    by augmentation, and a detection that finds no augmenting path when it joins never will:
//    the matched detections form a greedy basis of the transversal matroid).
//  - RemoveLabel(i): label i leaves; if it was matched, its detection searches one augmenting path
//    (any augmenting path in the smaller graph must end at that detection).
// Cost per operation O(edges) worst case, usually O(degree).
class IncrementalMatching {
 public:
  IncrementalMatching() = default;  // empty; call Reset before use
  explicit IncrementalMatching(const DetAdjacency* adjacency) { Reset(adjacency); }

  // Starts over on `adjacency` (no detection added, no label removed), keeping the memory: an
  // evaluation builds one matching per frame, class and difficulty, and reuses one per thread.
  void Reset(const DetAdjacency* adjacency);

  // Returns true if the matching grew by one. Requires: j not added before.
  bool AddDet(int j);
  // Returns the change of the matching size: 0 or -1. Requires: i present.
  int RemoveLabel(int i);

  int size() const { return size_; }
  int label_match(int i) const { return label_match_[i]; }  // detection or -1
  int det_match(int j) const { return det_match_[j]; }      // label or -1

 private:
  bool Augment(int j);

  const DetAdjacency* adj_ = nullptr;
  std::vector<int32_t> label_match_, det_match_;
  std::vector<uint8_t> label_removed_, det_added_;
  std::vector<int32_t> visit_stamp_;
  int32_t stamp_ = 0;
  int size_ = 0;
};

// A weight compared lexicographically: first the integer part, then the real part.
struct LexWeight {
  int64_t major = 0;
  double minor = 0.0;
};

struct WeightedEdge {
  int32_t label = 0, det = 0;
  LexWeight weight;  // must be > 0 (major > 0, or major == 0 and minor > 0)
};

// A matching of maximum total weight (sum of LexWeight, compared lexicographically) among
// `num_labels` x `num_dets` vertices and the given edges (at most one per pair, weights > 0). The
// Hungarian algorithm in its sparse form (successive shortest paths with potentials, Dijkstra on
// the reduced costs): O(n E log n) worst case, O(n^3) on a dense graph. Returns label -> detection
// or -1.
std::vector<int32_t> MaxWeightAssignment(int num_labels, int num_dets,
                                         const std::vector<WeightedEdge>& edges);

}  // namespace stereodet

#endif  // STEREODET_EVAL_BIPARTITE_INTERNAL_H_
