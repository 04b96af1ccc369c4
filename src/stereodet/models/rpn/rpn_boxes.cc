#include "stereodet/models/rpn/rpn_boxes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "stereodet/geometry/iou.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {

// exp() of a size delta stays below 1000 / 16, as in Detectron.
const double kMaxSizeDelta = std::log(1000.0 / 16.0);

bool NonEmpty(const Box2D& box) { return box.Width() > 0.0 && box.Height() > 0.0; }

Box2D Clip(const Box2D& box, int width, int height) {
  return {std::clamp(box.left, 0.0, double(width)), std::clamp(box.top, 0.0, double(height)),
          std::clamp(box.right, 0.0, double(width)), std::clamp(box.bottom, 0.0, double(height))};
}

}  // namespace

void AnchorOptions::Check() const {
  STEREODET_CHECK(stride_px >= 1) << "anchor stride must be >= 1 px, got " << stride_px;
  STEREODET_CHECK(!sizes_px.empty() && !ratios.empty()) << "need at least one size and one ratio";
  for (double s : sizes_px) {
    STEREODET_CHECK(s > 0.0 && std::isfinite(s)) << "anchor sizes must be > 0 px, got " << s;
  }
  for (double r : ratios) {
    STEREODET_CHECK(r > 0.0 && std::isfinite(r)) << "anchor ratios must be > 0, got " << r;
  }
}

std::vector<Box2D> GenerateRpnAnchors(int map_width, int map_height, const AnchorOptions& options) {
  options.Check();
  STEREODET_CHECK(map_width >= 1 && map_height >= 1)
      << "feature map must be at least 1 x 1, got " << map_width << " x " << map_height;
  std::vector<Box2D> anchors;
  anchors.reserve(static_cast<size_t>(map_width) * map_height * options.AnchorsPerCell());
  for (int row = 0; row < map_height; ++row) {
    for (int col = 0; col < map_width; ++col) {
      const double cx = (col + 0.5) * options.stride_px, cy = (row + 0.5) * options.stride_px;
      for (double size : options.sizes_px) {
        for (double ratio : options.ratios) {
          const double w = size / std::sqrt(ratio), h = size * std::sqrt(ratio);
          anchors.push_back({cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2});
        }
      }
    }
  }
  return anchors;
}

std::array<float, 4> EncodeDeltas(const Box2D& box, const Box2D& reference,
                                  const DeltaWeights& weights) {
  STEREODET_CHECK(NonEmpty(box) && NonEmpty(reference)) << "boxes must have a positive size";
  const double rw = reference.Width(), rh = reference.Height();
  const double rcx = reference.left + rw / 2, rcy = reference.top + rh / 2;
  const double w = box.Width(), h = box.Height();
  const double cx = box.left + w / 2, cy = box.top + h / 2;
  return {static_cast<float>(weights.x * (cx - rcx) / rw),
          static_cast<float>(weights.y * (cy - rcy) / rh),
          static_cast<float>(weights.w * std::log(w / rw)),
          static_cast<float>(weights.h * std::log(h / rh))};
}

Box2D DecodeDeltas(const float* deltas, const Box2D& reference, const DeltaWeights& weights) {
  const double rw = reference.Width(), rh = reference.Height();
  const double rcx = reference.left + rw / 2, rcy = reference.top + rh / 2;
  const double cx = rcx + deltas[0] / weights.x * rw, cy = rcy + deltas[1] / weights.y * rh;
  const double w = rw * std::exp(std::min(deltas[2] / weights.w, kMaxSizeDelta));
  const double h = rh * std::exp(std::min(deltas[3] / weights.h, kMaxSizeDelta));
  return {cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2};
}

void AnchorSamplingOptions::Check() const {
  STEREODET_CHECK(negative_iou >= 0.0 && negative_iou <= positive_iou && positive_iou <= 1.0)
      << "need 0 <= negative_iou <= positive_iou <= 1, got " << negative_iou << ", "
      << positive_iou;
  STEREODET_CHECK(ignore_iou >= 0.0 && ignore_iou <= 1.0)
      << "ignore_iou must be in [0, 1], got " << ignore_iou;
  STEREODET_CHECK(samples_per_image >= 1)
      << "samples_per_image must be >= 1, got " << samples_per_image;
  STEREODET_CHECK(positive_fraction > 0.0 && positive_fraction <= 1.0)
      << "positive_fraction must be in (0, 1], got " << positive_fraction;
}

std::vector<int> RandomSubset(int n, int k, std::mt19937_64& rng) {
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  k = std::clamp(k, 0, n);
  for (int i = 0; i < k; ++i) {
    const int j = i + static_cast<int>(rng() % static_cast<uint64_t>(n - i));
    std::swap(order[i], order[j]);
  }
  order.resize(k);
  std::sort(order.begin(), order.end());
  return order;
}

RpnAnchorTargets SampleAnchors(const std::vector<Box2D>& anchors,
                               const std::vector<TargetBox>& objects,
                               const AnchorSamplingOptions& options, std::mt19937_64& rng) {
  options.Check();
  const int n = static_cast<int>(anchors.size());
  std::vector<const TargetBox*> positives_of, ignores;
  for (const TargetBox& o : objects) {
    if (!NonEmpty(o.box)) continue;
    (o.label >= 1 ? positives_of : ignores).push_back(&o);
  }
  const int m = static_cast<int>(positives_of.size());
  std::vector<double> best_iou(n, 0.0);
  std::vector<int> best_object(n, -1);
  std::vector<double> object_best(m, 0.0);
  std::vector<double> iou(static_cast<size_t>(n) * m);
  for (int a = 0; a < n; ++a) {
    for (int k = 0; k < m; ++k) {
      const double v = Iou2D(anchors[a], positives_of[k]->box);
      iou[static_cast<size_t>(a) * m + k] = v;
      if (v > best_iou[a]) {
        best_iou[a] = v;
        best_object[a] = k;
      }
      object_best[k] = std::max(object_best[k], v);
    }
  }
  // -2 undecided, -1 ignored, 0 negative, 1 positive (before sampling).
  std::vector<int> state(n, -2);
  std::vector<int> assigned(best_object);
  for (int a = 0; a < n; ++a) {
    if (best_iou[a] >= options.positive_iou && m > 0) state[a] = 1;
  }
  // Each object's best anchors (ties included) are positives for it.
  for (int k = 0; k < m; ++k) {
    if (object_best[k] <= 0.0) continue;
    for (int a = 0; a < n; ++a) {
      if (iou[static_cast<size_t>(a) * m + k] == object_best[k]) {
        state[a] = 1;
        assigned[a] = k;
      }
    }
  }
  for (int a = 0; a < n; ++a) {
    if (state[a] == 1) continue;
    bool ignored = best_iou[a] >= options.negative_iou;
    for (const TargetBox* g : ignores) {
      if (ignored) break;
      ignored = Iou2D(anchors[a], g->box) >= options.ignore_iou;
    }
    state[a] = ignored ? -1 : 0;
  }
  std::vector<int> positive, negative;
  for (int a = 0; a < n; ++a) {
    if (state[a] == 1) positive.push_back(a);
    if (state[a] == 0) negative.push_back(a);
  }
  const int max_positive = std::max(
      1, static_cast<int>(std::floor(options.samples_per_image * options.positive_fraction)));
  RpnAnchorTargets targets;
  targets.labels.assign(n, -1);
  targets.deltas.assign(static_cast<size_t>(n) * 4, 0.0f);
  for (int i : RandomSubset(static_cast<int>(positive.size()), max_positive, rng)) {
    const int a = positive[i];
    targets.labels[a] = 1;
    const std::array<float, 4> d = EncodeDeltas(positives_of[assigned[a]]->box, anchors[a]);
    std::copy(d.begin(), d.end(), targets.deltas.begin() + static_cast<size_t>(a) * 4);
    ++targets.num_positive;
  }
  const int max_negative = options.samples_per_image - targets.num_positive;
  for (int i : RandomSubset(static_cast<int>(negative.size()), max_negative, rng)) {
    targets.labels[negative[i]] = 0;
    ++targets.num_negative;
  }
  return targets;
}

void ProposalOptions::Check() const {
  STEREODET_CHECK(pre_nms_top_n >= 1) << "pre_nms_top_n must be >= 1, got " << pre_nms_top_n;
  STEREODET_CHECK(post_nms_top_n >= 1) << "post_nms_top_n must be >= 1, got " << post_nms_top_n;
  STEREODET_CHECK(nms_iou >= 0.0 && nms_iou <= 1.0)
      << "proposal nms_iou must be in [0, 1], got " << nms_iou;
  STEREODET_CHECK(min_size_px >= 0.0) << "min_size_px must be >= 0, got " << min_size_px;
}

std::vector<ScoredBox> SelectProposals(const float* scores, const float* deltas,
                                       const std::vector<Box2D>& anchors, int image_width,
                                       int image_height, const ProposalOptions& options) {
  options.Check();
  const int n = static_cast<int>(anchors.size());
  // The top-scored anchors first (ties: lower index), so only those are decoded.
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  const int top = std::min(n, options.pre_nms_top_n);
  std::partial_sort(order.begin(), order.begin() + top, order.end(), [&](int a, int b) {
    return scores[a] != scores[b] ? scores[a] > scores[b] : a < b;
  });
  std::vector<ScoredBox> candidates;
  candidates.reserve(top);
  for (int i = 0; i < top; ++i) {
    const int a = order[i];
    const Box2D box = Clip(DecodeDeltas(deltas + static_cast<size_t>(a) * 4, anchors[a]),
                           image_width, image_height);
    if (box.Width() < options.min_size_px || box.Height() < options.min_size_px) continue;
    if (!std::isfinite(scores[a])) continue;
    candidates.push_back({box, scores[a], 0});
  }
  NmsOptions nms;
  nms.iou_threshold = options.nms_iou;
  nms.score_threshold = -std::numeric_limits<float>::infinity();
  nms.max_detections = options.post_nms_top_n;
  return NonMaximumSuppression(candidates, nms);
}

void RoiSamplingOptions::Check() const {
  STEREODET_CHECK(background_iou >= 0.0 && background_iou <= foreground_iou &&
                  foreground_iou <= 1.0)
      << "need 0 <= background_iou <= foreground_iou <= 1, got " << background_iou << ", "
      << foreground_iou;
  STEREODET_CHECK(ignore_iou >= 0.0 && ignore_iou <= 1.0)
      << "ignore_iou must be in [0, 1], got " << ignore_iou;
  STEREODET_CHECK(samples_per_image >= 1)
      << "samples_per_image must be >= 1, got " << samples_per_image;
  STEREODET_CHECK(foreground_fraction > 0.0 && foreground_fraction <= 1.0)
      << "foreground_fraction must be in (0, 1], got " << foreground_fraction;
}

RoiTargets SampleRois(const std::vector<ScoredBox>& proposals,
                      const std::vector<TargetBox>& objects, const RoiSamplingOptions& options,
                      std::mt19937_64& rng) {
  options.Check();
  std::vector<const TargetBox*> classed, ignores;
  for (const TargetBox& o : objects) {
    if (!NonEmpty(o.box)) continue;
    (o.label >= 1 ? classed : ignores).push_back(&o);
  }
  std::vector<Box2D> candidates;
  candidates.reserve(proposals.size() + classed.size());
  for (const ScoredBox& p : proposals) {
    if (NonEmpty(p.box)) candidates.push_back(p.box);
  }
  for (const TargetBox* o : classed) candidates.push_back(o->box);
  std::vector<int> foreground, background, object_of(candidates.size(), -1);
  for (size_t c = 0; c < candidates.size(); ++c) {
    double best = 0.0;
    for (size_t k = 0; k < classed.size(); ++k) {
      const double v = Iou2D(candidates[c], classed[k]->box);
      if (v > best) {
        best = v;
        object_of[c] = static_cast<int>(k);
      }
    }
    if (best >= options.foreground_iou) {
      foreground.push_back(static_cast<int>(c));
    } else if (best < options.background_iou) {
      const bool ignored = std::any_of(ignores.begin(), ignores.end(), [&](const TargetBox* g) {
        return Iou2D(candidates[c], g->box) >= options.ignore_iou;
      });
      if (!ignored) background.push_back(static_cast<int>(c));
    }
  }
  const int max_foreground = std::max(
      1, static_cast<int>(std::floor(options.samples_per_image * options.foreground_fraction)));
  RoiTargets targets;
  for (int i : RandomSubset(static_cast<int>(foreground.size()), max_foreground, rng)) {
    const int c = foreground[i];
    const TargetBox& o = *classed[object_of[c]];
    targets.rois.push_back(candidates[c]);
    targets.labels.push_back(o.label);
    const std::array<float, 4> d = EncodeDeltas(o.box, candidates[c], kHeadDeltaWeights);
    targets.deltas.insert(targets.deltas.end(), d.begin(), d.end());
    ++targets.num_foreground;
  }
  const int max_background = options.samples_per_image - targets.num_foreground;
  for (int i : RandomSubset(static_cast<int>(background.size()), max_background, rng)) {
    targets.rois.push_back(candidates[background[i]]);
    targets.labels.push_back(0);
    targets.deltas.insert(targets.deltas.end(), 4, 0.0f);
  }
  return targets;
}

void RpnDecodeOptions::Check() const {
  nms.Check();
  STEREODET_CHECK(score_threshold >= 0.0f && score_threshold <= 1.0f)
      << "score threshold must be in [0, 1], got " << score_threshold;
}

std::vector<ScoredBox> DecodeRpnDetections(const std::vector<Box2D>& rois,
                                           const float* probabilities, const float* deltas,
                                           int num_classes, int image_width, int image_height,
                                           const RpnDecodeOptions& options) {
  options.Check();
  std::vector<ScoredBox> candidates;
  for (size_t i = 0; i < rois.size(); ++i) {
    for (int k = 1; k <= num_classes; ++k) {
      const float score = probabilities[i * (num_classes + 1) + k];
      if (score < options.score_threshold) continue;
      const Box2D box =
          Clip(DecodeDeltas(deltas + (i * num_classes + k - 1) * 4, rois[i], kHeadDeltaWeights),
               image_width, image_height);
      if (!NonEmpty(box)) continue;
      candidates.push_back({box, score, k});
    }
  }
  return NonMaximumSuppression(candidates, options.nms);
}

}  // namespace stereodet
