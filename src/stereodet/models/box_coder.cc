#include "stereodet/models/box_coder.h"

#include <algorithm>
#include <cmath>

#include "stereodet/geometry/iou.h"
#include "stereodet/util/check.h"

namespace stereodet {

void BoxCoderOptions::Check() const {
  STEREODET_CHECK(center_variance > 0 && size_variance > 0)
      << "variances must be > 0, got " << center_variance << ", " << size_variance;
}

void MatchOptions::Check() const {
  coder.Check();
  STEREODET_CHECK(positive_iou > 0.0 && positive_iou <= 1.0)
      << "positive_iou must be in (0, 1], got " << positive_iou;
  STEREODET_CHECK(ignore_iou > 0.0 && ignore_iou <= 1.0)
      << "ignore_iou must be in (0, 1], got " << ignore_iou;
}

void DecodeOptions::Check() const {
  coder.Check();
  nms.Check();
  STEREODET_CHECK(score_threshold >= 0.0f && score_threshold < 1.0f)
      << "score_threshold must be in [0, 1), got " << score_threshold;
}

std::array<float, 4> EncodeBox(const Box2D& box, const DefaultBox& prior,
                               const BoxCoderOptions& options) {
  STEREODET_CHECK(box.Width() > 0 && box.Height() > 0) << "cannot encode an empty box";
  STEREODET_CHECK(prior.w > 0 && prior.h > 0) << "default box must have a positive size";
  const double cx = 0.5 * (box.left + box.right);
  const double cy = 0.5 * (box.top + box.bottom);
  return {static_cast<float>((cx - prior.cx) / prior.w / options.center_variance),
          static_cast<float>((cy - prior.cy) / prior.h / options.center_variance),
          static_cast<float>(std::log(box.Width() / prior.w) / options.size_variance),
          static_cast<float>(std::log(box.Height() / prior.h) / options.size_variance)};
}

Box2D DecodeBox(const float* deltas, const DefaultBox& prior, const BoxCoderOptions& options) {
  // Untrained networks can emit huge size deltas; clamp so exp() stays finite.
  const double max_log = std::log(1000.0);
  const double cx = prior.cx + static_cast<double>(deltas[0]) * options.center_variance * prior.w;
  const double cy = prior.cy + static_cast<double>(deltas[1]) * options.center_variance * prior.h;
  const double w =
      prior.w * std::exp(std::min(static_cast<double>(deltas[2]) * options.size_variance, max_log));
  const double h =
      prior.h * std::exp(std::min(static_cast<double>(deltas[3]) * options.size_variance, max_log));
  return {cx - w / 2.0, cy - h / 2.0, cx + w / 2.0, cy + h / 2.0};
}

MatchResult MatchDefaultBoxes(const std::vector<DefaultBox>& priors,
                              const std::vector<TargetBox>& objects, const MatchOptions& options) {
  options.Check();
  const int num_priors = static_cast<int>(priors.size());
  MatchResult result;
  result.labels.assign(num_priors, 0);
  result.deltas.assign(4 * static_cast<size_t>(num_priors), 0.0f);

  std::vector<Box2D> prior_boxes;
  prior_boxes.reserve(num_priors);
  for (const DefaultBox& p : priors) prior_boxes.push_back(p.ToBox2D());

  std::vector<int> object_index;  // objects that take part (label >= 1, non-empty)
  std::vector<int> ignore_index;
  for (int i = 0; i < static_cast<int>(objects.size()); ++i) {
    if (objects[i].box.Width() <= 0 || objects[i].box.Height() <= 0) continue;
    if (objects[i].label >= 1) {
      object_index.push_back(i);
    } else if (objects[i].label == kIgnoreLabel) {
      ignore_index.push_back(i);
    }
  }

  // best object per prior, and best prior per object
  std::vector<int> best_object(num_priors, -1);
  std::vector<double> best_iou(num_priors, 0.0);
  std::vector<int> best_prior(object_index.size(), -1);
  std::vector<double> best_prior_iou(object_index.size(), -1.0);
  for (int j = 0; j < num_priors; ++j) {
    for (size_t k = 0; k < object_index.size(); ++k) {
      const double iou = Iou2D(prior_boxes[j], objects[object_index[k]].box);
      if (iou > best_iou[j]) {
        best_iou[j] = iou;
        best_object[j] = static_cast<int>(k);
      }
      if (iou > best_prior_iou[k]) {
        best_prior_iou[k] = iou;
        best_prior[k] = j;
      }
    }
  }
  // Every object claims its best prior, whatever the IoU (SSD's bipartite step), unless it overlaps
  // no prior at all (it would steal an arbitrary one).
  for (size_t k = 0; k < object_index.size(); ++k) {
    if (best_prior[k] < 0 || best_prior_iou[k] <= 0.0) continue;
    best_object[best_prior[k]] = static_cast<int>(k);
    best_iou[best_prior[k]] = 2.0;  // above any threshold
  }
  for (int j = 0; j < num_priors; ++j) {
    if (best_object[j] >= 0 && best_iou[j] >= options.positive_iou) {
      const TargetBox& object = objects[object_index[best_object[j]]];
      result.labels[j] = object.label;
      const std::array<float, 4> d = EncodeBox(object.box, priors[j], options.coder);
      std::copy(d.begin(), d.end(), result.deltas.begin() + 4 * static_cast<size_t>(j));
      ++result.num_positive;
    } else {
      for (int i : ignore_index) {
        if (Iou2D(prior_boxes[j], objects[i].box) >= options.ignore_iou) {
          result.labels[j] = kIgnoreLabel;
          break;
        }
      }
    }
  }
  return result;
}

std::vector<ScoredBox> DecodeDetections(const float* deltas, const float* probabilities,
                                        int num_classes, const std::vector<DefaultBox>& priors,
                                        const DecodeOptions& options) {
  options.Check();
  STEREODET_CHECK(num_classes >= 2) << "need background plus at least one class";
  std::vector<ScoredBox> candidates;
  for (size_t j = 0; j < priors.size(); ++j) {
    const float* p = probabilities + j * num_classes;
    bool decoded = false;
    Box2D box;
    for (int c = 1; c < num_classes; ++c) {
      if (p[c] < options.score_threshold) continue;
      if (!decoded) {
        box = DecodeBox(deltas + 4 * j, priors[j], options.coder);
        decoded = true;
      }
      candidates.push_back({box, p[c], c});
    }
  }
  return NonMaximumSuppression(candidates, options.nms);
}

std::vector<Object> ToKittiDetections(const std::vector<ScoredBox>& boxes,
                                      const std::vector<std::string>& classes, double scale_x,
                                      double scale_y, int image_width, int image_height) {
  std::vector<Object> objects;
  for (const ScoredBox& b : boxes) {
    STEREODET_CHECK(b.label >= 1 && b.label <= static_cast<int>(classes.size()))
        << "detection label " << b.label << " out of range";
    Object o;
    o.type = classes[b.label - 1];
    o.truncated = -1.0;
    o.occluded = -1;
    // Rounded to 0.01 px (KITTI's own precision; the files stay short and read back exactly).
    auto px = [](double v, double hi) {
      return std::round(std::clamp(v, 0.0, hi) * 100.0) / 100.0;
    };
    o.box = {px(b.box.left * scale_x, image_width), px(b.box.top * scale_y, image_height),
             px(b.box.right * scale_x, image_width), px(b.box.bottom * scale_y, image_height)};
    if (o.box.Width() <= 0.0 || o.box.Height() <= 0.0) continue;
    o.SetNot3DEstimated();
    // Six decimals keep the ranking of all but near-identical scores.
    o.score = std::round(static_cast<double>(b.score) * 1e6) / 1e6;
    objects.push_back(o);
  }
  return objects;
}

}  // namespace stereodet
