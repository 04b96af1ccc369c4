#include "stereodet/synth/bvh.h"

#include <algorithm>
#include <array>
#include <functional>

namespace stereodet {

namespace {
constexpr int kBins = 12;
constexpr int kMaxLeafSize = 2;
// Traversal stack size. A traversal holds at most one entry per level, and the tree's depth is
// capped below this at build time (Build() makes leaves at kMaxDepth).
constexpr int kStackSize = 128;
constexpr int kMaxDepth = 100;
}  // namespace

Bvh::Bvh(const std::vector<Primitive>& primitives) {
  const int n = static_cast<int>(primitives.size());
  order_.resize(n);
  std::vector<Aabb> boxes(n);
  std::vector<Eigen::Vector3f> centres(n);
  for (int i = 0; i < n; ++i) {
    order_[i] = i;
    boxes[i] = primitives[i].Bounds();
    centres[i] = boxes[i].Centre();
  }
  nodes_.reserve(2 * std::max(n, 1));
  nodes_.push_back({});
  // With no primitives node 0 stays an empty placeholder; the queries check for that first.
  if (n > 0) Build(0, 0, n, 0, boxes, centres);
  primitives_.reserve(n);
  for (int i = 0; i < n; ++i) primitives_.push_back(primitives[order_[i]]);
}

// Builds the subtree over order_[begin, end) into the existing slot `node`. Children are allocated
// as a pair so that an inner node needs only the left child's index.
void Bvh::Build(int node, int begin, int end, int depth, const std::vector<Aabb>& boxes,
                const std::vector<Eigen::Vector3f>& centres) {
  Aabb bounds, centre_bounds;
  for (int i = begin; i < end; ++i) {
    bounds.Extend(boxes[order_[i]]);
    centre_bounds.Extend(centres[order_[i]]);
  }
  nodes_[node].bounds = bounds;
  const int count = end - begin;
  if (count <= kMaxLeafSize || depth >= kMaxDepth) {
    nodes_[node].first = begin;
    nodes_[node].count = count;
    return;
  }
  // Binned SAH, tried on all three axes, the cheapest split kept.
  float best_cost = kNoHit;
  int best_axis = -1, best_split = -1;
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = centre_bounds.min[axis], hi = centre_bounds.max[axis];
    if (hi - lo < 1e-6f) continue;
    std::array<Aabb, kBins> bin_bounds;
    std::array<int, kBins> bin_count{};
    const float scale = kBins / (hi - lo);
    for (int i = begin; i < end; ++i) {
      const int b = std::min(kBins - 1, static_cast<int>((centres[order_[i]][axis] - lo) * scale));
      bin_bounds[b].Extend(boxes[order_[i]]);
      ++bin_count[b];
    }
    std::array<float, kBins> right_cost{};
    Aabb acc;
    int acc_count = 0;
    for (int b = kBins - 1; b > 0; --b) {
      acc.Extend(bin_bounds[b]);
      acc_count += bin_count[b];
      right_cost[b] = acc_count == 0 ? 0.0f : acc.SurfaceArea() * acc_count;
    }
    acc = Aabb();
    acc_count = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      acc.Extend(bin_bounds[b]);
      acc_count += bin_count[b];
      if (acc_count == 0 || acc_count == count) continue;
      const float cost = acc.SurfaceArea() * acc_count + right_cost[b + 1];
      if (cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_split = b;
      }
    }
  }
  int mid = begin + count / 2;  // all centroids coincide: split the range in half
  if (best_axis >= 0) {
    const float lo = centre_bounds.min[best_axis];
    const float scale = kBins / (centre_bounds.max[best_axis] - lo);
    const auto it = std::partition(order_.begin() + begin, order_.begin() + end, [&](int p) {
      return std::min(kBins - 1, static_cast<int>((centres[p][best_axis] - lo) * scale)) <=
             best_split;
    });
    mid = static_cast<int>(it - order_.begin());
    if (mid == begin || mid == end) mid = begin + count / 2;
  }
  const int left = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  nodes_[node].first = left;
  nodes_[node].count = 0;
  Build(left, begin, mid, depth + 1, boxes, centres);
  Build(left + 1, mid, end, depth + 1, boxes, centres);
}

int Bvh::depth() const {
  std::function<int(int)> rec = [&](int i) -> int {
    if (nodes_[i].count > 0) return 1;
    return 1 + std::max(rec(nodes_[i].first), rec(nodes_[i].first + 1));
  };
  return nodes_.empty() ? 0 : rec(0);
}

RayHit Bvh::Intersect(const Ray& ray, float t_min, float t_max) const {
  RayHit hit;
  if (primitives_.empty() || nodes_[0].bounds.Intersect(ray, t_min, t_max) == kNoHit) return hit;
  // The stack keeps each pushed node's entry distance, so a node made too far by a hit found
  // after it was pushed is dropped without testing its box again.
  std::array<std::pair<int, float>, kStackSize> stack;
  int top = 0;
  int node = 0;
  while (true) {
    const Node& n = nodes_[node];
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const float t = primitives_[i].Intersect(ray, t_min, t_max);
        if (t < t_max) {
          t_max = t;
          hit.t = t;
          hit.primitive = order_[i];
        }
      }
    } else {
      int first = n.first, second = n.first + 1;
      float ta = nodes_[first].bounds.Intersect(ray, t_min, t_max);
      float tb = nodes_[second].bounds.Intersect(ray, t_min, t_max);
      if (tb < ta) {
        std::swap(ta, tb);
        std::swap(first, second);
      }
      if (ta != kNoHit) {
        if (tb != kNoHit) stack[top++] = {second, tb};
        node = first;
        continue;
      }
    }
    bool found = false;
    while (top > 0) {
      const auto [candidate, t_entry] = stack[--top];
      if (t_entry < t_max) {
        node = candidate;
        found = true;
        break;
      }
    }
    if (!found) break;
  }
  return hit;
}

RayHit Bvh::AnyHit(const Ray& ray, float t_min, float t_max) const {
  if (primitives_.empty() || nodes_[0].bounds.Intersect(ray, t_min, t_max) == kNoHit) return {};
  std::array<int, kStackSize> stack;
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (n.bounds.Intersect(ray, t_min, t_max) == kNoHit) continue;
    if (n.count > 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const float t = primitives_[i].Intersect(ray, t_min, t_max);
        if (t != kNoHit) return {t, order_[i]};
      }
    } else {
      stack[top++] = n.first + 1;
      stack[top++] = n.first;
    }
  }
  return {};
}

}  // namespace stereodet
