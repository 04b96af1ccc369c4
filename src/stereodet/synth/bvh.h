// A bounding volume hierarchy over a scene's primitives, for closest-hit and any-hit ray queries.
//
// Built once per frame with a binned surface-area heuristic (a few hundred primitives: well under
// a millisecond); traversed with a small explicit stack, nearer child first, so that the closest
// hit found so far prunes the rest (the caller passes the analytic ground plane's hit as t_max,
// which removes most of the work for rays that look down at the road).
#ifndef STEREODET_SYNTH_BVH_H_
#define STEREODET_SYNTH_BVH_H_

#include <vector>

#include "stereodet/synth/shapes.h"

namespace stereodet {

struct RayHit {
  float t = kNoHit;    // ray parameter of the hit, kNoHit if none
  int primitive = -1;  // index into the primitive array the Bvh was built over
};

class Bvh {
 public:
  Bvh() = default;
  // Builds over a copy of `primitives` (stored in traversal order, so the Bvh is self-contained and
  // a Scene holding one may be copied or moved freely).
  explicit Bvh(const std::vector<Primitive>& primitives);

  // Closest primitive hit with t in (t_min, t_max).
  RayHit Intersect(const Ray& ray, float t_min, float t_max) const;
  // Some primitive hit with t in (t_min, t_max), not necessarily the closest (shadow rays);
  // stops at the first found. primitive = -1 if none.
  RayHit AnyHit(const Ray& ray, float t_min, float t_max) const;

  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  int depth() const;

 private:
  struct Node {
    Aabb bounds;
    int first = 0;  // leaf: first index into order_; inner: index of the left child (right = +1)
    int count = 0;  // leaf: number of primitives (> 0); inner: 0
  };
  void Build(int node, int begin, int end, int depth, const std::vector<Aabb>& boxes,
             const std::vector<Eigen::Vector3f>& centres);

  std::vector<Node> nodes_;
  std::vector<int> order_;             // original primitive indices; leaves own ranges of it
  std::vector<Primitive> primitives_;  // primitives_[i] is the original primitive order_[i]
};

}  // namespace stereodet

#endif  // STEREODET_SYNTH_BVH_H_
