#include "stereodet/eval/curves.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <utility>

#include "stereodet/util/check.h"

namespace stereodet {

CurvePoint FinishPoint(CurvePoint p) {
  p.precision =
      p.tp + p.fp > 0 ? static_cast<double>(p.tp) / static_cast<double>(p.tp + p.fp) : 0.0;
  p.recall = p.tp + p.fn > 0 ? static_cast<double>(p.tp) / static_cast<double>(p.tp + p.fn) : 0.0;
  p.orientation = p.tp + p.fp > 0 ? p.similarity / static_cast<double>(p.tp + p.fp) : 0.0;
  return p;
}

namespace {

// The positions of `events` in descending score, equal scores in their order in `events` (a
// stable sort; -0 and +0 are one score). An LSD radix sort on the scores' bits, byte by byte,
// skipping the bytes every score shares: several times faster than a comparison sort on the tens
// of thousands of events of a curve. With a NaN score (no order), std::stable_sort's.
std::vector<uint32_t> DescendingScoreOrder(const std::vector<CurveEvent>& events) {
  const size_t n = events.size();
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  const bool any_nan = std::any_of(events.begin(), events.end(),
                                   [](const CurveEvent& e) { return std::isnan(e.score); });
  if (n < 64 || any_nan) {
    std::stable_sort(order.begin(), order.end(),
                     [&](uint32_t a, uint32_t b) { return events[a].score > events[b].score; });
    return order;
  }
  // Keys whose ascending order is the scores' descending order: the IEEE bits made monotonic
  // (negative: all bits flipped; positive: the sign bit set), then complemented.
  std::vector<uint64_t> key(n), key_tmp(n);
  for (size_t i = 0; i < n; ++i) {
    const double score = events[i].score == 0.0 ? 0.0 : events[i].score;  // -0 as +0
    uint64_t bits;
    std::memcpy(&bits, &score, sizeof bits);
    bits = (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
    key[i] = ~bits;
  }
  std::vector<uint32_t> order_tmp(n);
  std::array<size_t, 257> count;
  for (int shift = 0; shift < 64; shift += 8) {
    count.fill(0);
    for (size_t i = 0; i < n; ++i) ++count[((key[i] >> shift) & 0xff) + 1];
    if (std::find(count.begin() + 1, count.end(), n) != count.end()) continue;  // one byte value
    for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
    for (size_t i = 0; i < n; ++i) {
      const size_t at = count[(key[i] >> shift) & 0xff]++;
      key_tmp[at] = key[i];
      order_tmp[at] = order[i];
    }
    key.swap(key_tmp);
    order.swap(order_tmp);
  }
  return order;
}

}  // namespace

std::vector<CurvePoint> BuildCurve(std::vector<CurveEvent> events, int64_t num_valid_labels) {
  STEREODET_CHECK_LE(events.size(), std::numeric_limits<uint32_t>::max())
      << "BuildCurve: too many curve events";
  const std::vector<uint32_t> order = DescendingScoreOrder(events);
  // At most one point per event: one allocation, not a doubling copy per power of two (the
  // curves of a 3769-frame set hold tens of thousands of points; their pages are faulted in
  // once instead of about twice).
  std::vector<CurvePoint> curve;
  curve.reserve(events.size());
  CurvePoint current;
  current.fn = num_valid_labels;
  for (size_t i = 0; i < order.size();) {
    const double score = events[order[i]].score;
    for (; i < order.size() && events[order[i]].score == score; ++i) {
      const CurveEvent& e = events[order[i]];
      current.tp += e.tp;
      current.fp += e.fp;
      current.fn += e.fn;
      current.similarity += e.similarity;
    }
    current.threshold = score;
    current = FinishPoint(current);
    curve.push_back(current);
  }
  return curve;
}

namespace {

double InterpolatedAp(const std::vector<CurvePoint>& curve, int first, int last, double step,
                      bool orientation = false) {
  // The mean over the recall levels r = k * step, k = first..last, of the best precision (or
  // orientation ratio) at recall >= r, 0 where no point reaches r. Points with no detection
  // (tp + fp = 0) take no part.
  auto value = [&](const CurvePoint& p) { return orientation ? p.orientation : p.precision; };
  bool any_nan = false;
  for (const CurvePoint& p : curve) any_nan |= std::isnan(p.recall) || std::isnan(value(p));
  if (any_nan) {
    // With a NaN, std::max depends on the order of its operands: the original way, by sorting.
    std::vector<std::pair<double, double>> pr;  // (recall, value)
    for (const CurvePoint& p : curve) {
      if (p.tp + p.fp > 0) pr.emplace_back(p.recall, value(p));
    }
    std::sort(pr.begin(), pr.end());
    for (size_t i = pr.size(); i-- > 1;)
      pr[i - 1].second = std::max(pr[i - 1].second, pr[i].second);
    double sum = 0.0;
    for (int k = first; k <= last; ++k) {
      const double r = k * step;
      const auto it = std::lower_bound(
          pr.begin(), pr.end(), r,
          [](const std::pair<double, double>& a, double v) { return a.first < v; });
      if (it != pr.end()) sum += it->second;
    }
    return sum / (last - first + 1) * 100.0;
  }
  // Without NaN the maximum of a set is exact whatever the order: each point raises the best value
  // of the highest level its recall reaches (levels reached form a prefix, k * step growing with
  // k), and a suffix maximum over the levels gives each level's best, in linear time. (No value is
  // -0: precisions are counts' ratios and similarity sums start at +0.)
  const int n_levels = last - first + 1;
  std::vector<double> best(n_levels, 0.0);
  std::vector<uint8_t> reached(n_levels, 0);
  for (const CurvePoint& p : curve) {
    if (p.tp + p.fp <= 0) continue;
    // The highest k in [first, last] with k * step <= recall (the levels lower_bound would find).
    int k = static_cast<int>(std::clamp(std::floor(p.recall / step), first - 1.0, last + 0.0));
    while (k + 1 <= last && (k + 1) * step <= p.recall) ++k;
    while (k >= first && !(k * step <= p.recall)) --k;
    if (k < first) continue;
    const int level = k - first;
    best[level] = reached[level] ? std::max(best[level], value(p)) : value(p);
    reached[level] = 1;
  }
  // Suffix maxima, in place: best[level] becomes the best value at recall >= that level's r.
  for (int level = n_levels - 2; level >= 0; --level) {
    if (!reached[level + 1]) continue;
    best[level] = reached[level] ? std::max(best[level], best[level + 1]) : best[level + 1];
    reached[level] = 1;
  }
  double sum = 0.0;  // in ascending level order, as the levels were always summed
  for (int level = 0; level < n_levels; ++level) {
    if (reached[level]) sum += best[level];
  }
  return sum / n_levels * 100.0;
}

}  // namespace

double InterpolatedApR40(const std::vector<CurvePoint>& curve) {
  return InterpolatedAp(curve, 1, 40, 1.0 / 40.0);
}

double InterpolatedApR11(const std::vector<CurvePoint>& curve) {
  return InterpolatedAp(curve, 0, 10, 1.0 / 10.0);
}

double InterpolatedAosR40(const std::vector<CurvePoint>& curve) {
  return InterpolatedAp(curve, 1, 40, 1.0 / 40.0, true);
}

double InterpolatedAosR11(const std::vector<CurvePoint>& curve) {
  return InterpolatedAp(curve, 0, 10, 1.0 / 10.0, true);
}

double EveryPointAp(const std::vector<CurvePoint>& curve) {
  std::vector<std::pair<double, double>> pr;
  pr.reserve(curve.size());
  for (const CurvePoint& p : curve) {
    if (p.tp + p.fp > 0) pr.emplace_back(p.recall, p.precision);
  }
  // A curve's recall rarely goes down with the threshold: then the points are in order already.
  const auto by_recall = [](const auto& a, const auto& b) { return a.first < b.first; };
  if (!std::is_sorted(pr.begin(), pr.end(), by_recall))
    std::stable_sort(pr.begin(), pr.end(), by_recall);
  std::vector<double> mrec, mpre;
  mrec.reserve(pr.size() + 2);
  mpre.reserve(pr.size() + 2);
  mrec.push_back(0.0);
  mpre.push_back(0.0);
  for (const auto& [r, p] : pr) {
    mrec.push_back(r);
    mpre.push_back(p);
  }
  mrec.push_back(1.0);
  mpre.push_back(0.0);
  for (size_t i = mpre.size() - 1; i-- > 0;) mpre[i] = std::max(mpre[i], mpre[i + 1]);
  double ap = 0.0;
  for (size_t i = 0; i + 1 < mrec.size(); ++i) {
    if (mrec[i + 1] != mrec[i]) ap += (mrec[i + 1] - mrec[i]) * mpre[i + 1];
  }
  return ap * 100.0;
}

OperatingPoint MakeOperatingPoint(double threshold, int64_t tp, int64_t fp, int64_t fn) {
  OperatingPoint op;
  op.threshold = threshold;
  op.tp = tp;
  op.fp = fp;
  op.fn = fn;
  op.precision = tp + fp > 0 ? static_cast<double>(tp) / static_cast<double>(tp + fp) : 0.0;
  op.recall = tp + fn > 0 ? static_cast<double>(tp) / static_cast<double>(tp + fn) : 0.0;
  op.f1 = op.precision + op.recall > 0 ? 2 * op.precision * op.recall / (op.precision + op.recall)
                                       : 0.0;
  return op;
}

OperatingPoint BestF1(const std::vector<CurvePoint>& curve) {
  OperatingPoint best;
  bool first = true;
  for (const CurvePoint& p : curve) {
    const OperatingPoint op = MakeOperatingPoint(p.threshold, p.tp, p.fp, p.fn);
    if (first || op.f1 > best.f1) {
      best = op;
      first = false;
    }
  }
  return best;
}

}  // namespace stereodet
