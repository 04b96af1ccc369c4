#include <algorithm>
#include <functional>
#include <limits>

#include "stereodet/eval/bipartite_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

void IncrementalMatching::Reset(const DetAdjacency* adjacency) {
  adj_ = adjacency;
  label_match_.assign(adjacency->num_labels, -1);
  det_match_.assign(adjacency->num_dets(), -1);
  label_removed_.assign(adjacency->num_labels, 0);
  det_added_.assign(adjacency->num_dets(), 0);
  visit_stamp_.assign(adjacency->num_labels, 0);
  stamp_ = 0;
  size_ = 0;
}

bool IncrementalMatching::Augment(int j) {
  const int32_t* begin = adj_->labels.data() + adj_->begin[j];
  const int32_t* end = adj_->labels.data() + adj_->begin[j + 1];
  // A free label next to j ends the path at once: the common case, found without recursion.
  for (const int32_t* p = begin; p != end; ++p) {
    const int i = *p;
    if (!label_removed_[i] && label_match_[i] < 0) {
      label_match_[i] = j;
      det_match_[j] = i;
      return true;
    }
  }
  for (const int32_t* p = begin; p != end; ++p) {
    const int i = *p;
    if (label_removed_[i] || visit_stamp_[i] == stamp_) continue;
    visit_stamp_[i] = stamp_;
    if (Augment(label_match_[i])) {
      label_match_[i] = j;
      det_match_[j] = i;
      return true;
    }
  }
  return false;
}

bool IncrementalMatching::AddDet(int j) {
  STEREODET_CHECK(!det_added_[j]) << "detection " << j << " added twice";
  det_added_[j] = 1;
  ++stamp_;
  if (Augment(j)) {
    ++size_;
    return true;
  }
  return false;
}

int IncrementalMatching::RemoveLabel(int i) {
  STEREODET_CHECK(!label_removed_[i]) << "label " << i << " removed twice";
  label_removed_[i] = 1;
  const int j = label_match_[i];
  if (j < 0) return 0;
  label_match_[i] = -1;
  det_match_[j] = -1;
  ++stamp_;
  if (Augment(j)) return 0;
  --size_;
  return -1;
}

namespace {

LexWeight operator+(LexWeight a, LexWeight b) { return {a.major + b.major, a.minor + b.minor}; }
LexWeight operator-(LexWeight a, LexWeight b) { return {a.major - b.major, a.minor - b.minor}; }
bool operator<(LexWeight a, LexWeight b) {
  return a.major != b.major ? a.major < b.major : a.minor < b.minor;
}

}  // namespace

std::vector<int32_t> MaxWeightAssignment(int num_labels, int num_dets,
                                         const std::vector<WeightedEdge>& edges) {
  std::vector<int32_t> result(num_labels, -1);
  if (num_labels == 0 || num_dets == 0 || edges.empty()) return result;
  // Min-cost assignment of every label (row) to a column: a detection (cost -weight) or the label's
  // own "unmatched" column (cost 0). Successive shortest paths (Dijkstra on reduced costs, i.e. the
  // Hungarian algorithm on the sparse graph): one search per label, O(E log V) each, so a component
  // with few edges per vertex costs far less than the dense O(n^3).
  const int nl = num_labels, nd = num_dets, nc = num_dets + num_labels;
  std::vector<int32_t> begin(nl + 1, 0);
  for (const WeightedEdge& e : edges) ++begin[e.label + 1];
  for (int i = 0; i < nl; ++i) begin[i + 1] += begin[i] + 1;  // + the unmatched column
  std::vector<int32_t> col(begin[nl]);
  std::vector<LexWeight> cost(begin[nl]);
  std::vector<int32_t> fill(begin.begin(), begin.end() - 1);
  for (int i = 0; i < nl; ++i) {
    col[fill[i]] = nd + i;
    cost[fill[i]++] = LexWeight{};
  }
  for (const WeightedEdge& e : edges) {
    col[fill[e.label]] = e.det;
    cost[fill[e.label]++] = LexWeight{-e.weight.major, -e.weight.minor};
  }
  // Potentials: u[row] = min cost of the row, v[col] = 0, so every reduced cost is >= 0.
  std::vector<LexWeight> u(nl), v(nc);
  for (int i = 0; i < nl; ++i) {
    LexWeight m{};
    for (int k = begin[i]; k < begin[i + 1]; ++k) {
      if (cost[k] < m) m = cost[k];
    }
    u[i] = m;
  }
  std::vector<int32_t> col_row(nc, -1), row_col(nl, -1), pred(nc, -1), finalized_cols;
  std::vector<LexWeight> dist(nc);
  std::vector<uint8_t> seen(nc, 0), done(nc, 0);
  struct Item {
    LexWeight d;
    int32_t c;
    bool operator>(const Item& o) const { return o.d < d; }
  };
  std::vector<Item> heap;
  for (int start = 0; start < nl; ++start) {
    std::vector<int32_t> touched;
    heap.clear();
    auto relax = [&](int r, LexWeight base) {
      for (int k = begin[r]; k < begin[r + 1]; ++k) {
        const int c = col[k];
        if (done[c]) continue;
        const LexWeight d = base + (cost[k] - u[r] - v[c]);
        if (!seen[c] || d < dist[c]) {
          if (!seen[c]) touched.push_back(c);
          seen[c] = 1;
          dist[c] = d;
          pred[c] = r;
          heap.push_back(Item{d, c});
          std::push_heap(heap.begin(), heap.end(), std::greater<Item>());
        }
      }
    };
    relax(start, LexWeight{});
    finalized_cols.clear();
    int free_col = -1;
    while (!heap.empty()) {
      std::pop_heap(heap.begin(), heap.end(), std::greater<Item>());
      const Item it = heap.back();
      heap.pop_back();
      if (done[it.c] || dist[it.c] < it.d) continue;
      done[it.c] = 1;
      if (col_row[it.c] < 0) {
        free_col = it.c;
        break;
      }
      finalized_cols.push_back(it.c);
      relax(col_row[it.c], dist[it.c]);
    }
    STEREODET_CHECK(free_col >= 0) << "assignment: no augmenting path (cannot happen)";
    const LexWeight total = dist[free_col];
    u[start] = u[start] + total;
    for (const int c : finalized_cols) {
      const LexWeight slack = total - dist[c];
      v[c] = v[c] - slack;
      u[col_row[c]] = u[col_row[c]] + slack;
    }
    // Augment along the predecessors.
    for (int c = free_col; c >= 0;) {
      const int r = pred[c];
      const int previous = row_col[r];
      col_row[c] = r;
      row_col[r] = c;
      c = r == start ? -1 : previous;
    }
    for (const int c : touched) seen[c] = done[c] = 0;
  }
  for (int i = 0; i < nl; ++i) {
    if (row_col[i] >= 0 && row_col[i] < nd) result[i] = row_col[i];
  }
  return result;
}

}  // namespace stereodet
