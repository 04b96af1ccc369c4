#include "stereodet/models/nms.h"

#include <algorithm>
#include <map>
#include <numeric>

#include "stereodet/geometry/iou.h"
#include "stereodet/util/check.h"

namespace stereodet {

void NmsOptions::Check() const {
  STEREODET_CHECK(iou_threshold >= 0.0 && iou_threshold <= 1.0)
      << "iou_threshold must be in [0, 1], got " << iou_threshold;
  STEREODET_CHECK(max_candidates_per_label >= 0)
      << "max_candidates_per_label must be >= 0, got " << max_candidates_per_label;
  STEREODET_CHECK(max_detections >= 0) << "max_detections must be >= 0, got " << max_detections;
}

std::vector<ScoredBox> NonMaximumSuppression(const std::vector<ScoredBox>& boxes,
                                             const NmsOptions& options) {
  options.Check();
  // Indices per label, so each label's suppression loop only compares boxes of that label.
  std::map<int, std::vector<int>> by_label;
  for (int i = 0; i < static_cast<int>(boxes.size()); ++i) {
    if (boxes[i].score >= options.score_threshold) by_label[boxes[i].label].push_back(i);
  }
  auto higher = [&boxes](int a, int b) {
    return boxes[a].score != boxes[b].score ? boxes[a].score > boxes[b].score : a < b;
  };
  std::vector<int> kept_all;
  for (auto& [label, indices] : by_label) {
    std::stable_sort(indices.begin(), indices.end(), higher);
    if (options.max_candidates_per_label > 0 &&
        static_cast<int>(indices.size()) > options.max_candidates_per_label) {
      indices.resize(options.max_candidates_per_label);
    }
    std::vector<int> kept;
    for (int i : indices) {
      const Box2D& candidate = boxes[i].box;
      const bool suppressed = std::any_of(kept.begin(), kept.end(), [&](int k) {
        return Iou2D(boxes[k].box, candidate) > options.iou_threshold;
      });
      if (!suppressed) kept.push_back(i);
    }
    kept_all.insert(kept_all.end(), kept.begin(), kept.end());
  }
  std::stable_sort(kept_all.begin(), kept_all.end(), higher);
  if (options.max_detections > 0 && static_cast<int>(kept_all.size()) > options.max_detections) {
    kept_all.resize(options.max_detections);
  }
  std::vector<ScoredBox> result;
  result.reserve(kept_all.size());
  for (int i : kept_all) result.push_back(boxes[i]);
  return result;
}

}  // namespace stereodet
