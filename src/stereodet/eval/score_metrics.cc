#include "stereodet/eval/score_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "stereodet/eval/score_metrics_internal.h"
#include "stereodet/util/check.h"

namespace stereodet {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const double pos = q * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(values.size() - 1, lo + 1);
  const double frac = pos - static_cast<double>(lo);
  return values[lo] + (values[hi] - values[lo]) * frac;
}

BrierScores WithoutProbabilities(BrierScores brier) {
  brier.over_labels = brier.over_detections = brier.over_all = kNaN;
  return brier;
}

CalibrationResult WithoutProbabilities(CalibrationResult calibration) {
  calibration.ece = calibration.laece = kNaN;
  for (ReliabilityBin& bin : calibration.bins) {
    bin.mean_score = bin.tp_fraction = bin.mean_iou = kNaN;
  }
  return calibration;
}

ScoreMetricsAccumulator::ScoreMetricsAccumulator(int calibration_bins, double distance_bin_m,
                                                 double max_distance_m, ScoreTransform transform)
    : bin_count_(calibration_bins, 0),
      bin_tp_(calibration_bins, 0),
      bin_score_sum_(calibration_bins, 0.0),
      bin_iou_sum_(calibration_bins, 0.0),
      distance_bin_m_(distance_bin_m),
      max_distance_m_(max_distance_m),
      transform_(transform) {
  STEREODET_CHECK_GE(calibration_bins, 1);
  STEREODET_CHECK_GT(distance_bin_m, 0);
  STEREODET_CHECK_GT(max_distance_m, 0);
  const int num_distance_bins = static_cast<int>(std::ceil(max_distance_m / distance_bin_m));
  centre_errors_.resize(num_distance_bins);
  depth_errors_.resize(num_distance_bins);
}

void ScoreMetricsAccumulator::Add(const EvalFrame& frame, const ClassFrame& cf,
                                  const FrameAssociation& a, Difficulty difficulty,
                                  const StableSelection* selection, const DeceCell* dece_cells) {
  if (selection == nullptr) {
    AddKept(frame, cf, a, difficulty, KeepEverything{}, dece_cells);
  } else {
    AddKept(frame, cf, a, difficulty, MaskSelection(frame, cf, selection).Bin(0), dece_cells);
  }
}

void ScoreMetricsAccumulator::DeceCells(const EvalFrame& frame, const ClassFrame& cf,
                                        DeceCell* out) const {
  for (int j = 0; j < cf.num_dets(); ++j) {
    out[j] = DeceCellOf(ApplyScoreTransform(transform_, cf.det_score[j]),
                        &frame.detections[cf.det_object[j]].box);
  }
}

namespace {

// A TP detection j's overlap with its label in `a` (its edge among the label's), for LaECE.
double TpOverlap(const ClassFrame& cf, const FrameAssociation& a, int j) {
  const int e = cf.FindEdge(a.det_label[j], j);
  return e >= 0 ? cf.edge_overlap[e] : ScoreMetricsAccumulator::kUnknownOverlap;
}

}  // namespace

ScoreMetricsAccumulator::DeceCell ScoreMetricsAccumulator::DeceCellOf(
    const EvalFrame& frame, const ClassFrame& cf, int j, double s,
    const DeceCell* dece_cells) const {
  return dece_cells != nullptr ? dece_cells[j]
                               : DeceCellOf(s, &frame.detections[cf.det_object[j]].box);
}

void ScoreMetricsAccumulator::AddToBins(const EvalFrame& frame, const ClassFrame& cf,
                                        const FrameAssociation& a, Difficulty difficulty,
                                        const BinMasks& masks, size_t n_s,
                                        ScoreMetricsAccumulator* accs, const DeceCell* dece_cells) {
  if (n_s == 0) return;
  // Add's terms, each made once and given to every bin that keeps it.
  ForEachBrierTerm(
      cf, a, difficulty, accs[0].transform_, KeepEverything{},
      [&](double term, int i, int j) {
        for (size_t k = 0; k < n_s; ++k) {
          const MaskView mask = masks.Bin(k);
          if (j >= 0 ? mask.KeepsPair(i, j) : mask.KeepsLabel(i)) accs[k].AddLabelTerm(term);
        }
      },
      [&](double s, Outcome o, int j) {
        const bool tp = o == Outcome::kTp;
        const double overlap = tp ? TpOverlap(cf, a, j) : 0.0;
        const DeceCell cell = accs[0].DeceCellOf(frame, cf, j, s, dece_cells);
        for (size_t k = 0; k < n_s; ++k) {
          const MaskView mask = masks.Bin(k);
          if (tp ? mask.KeepsPair(a.det_label[j], j) : mask.KeepsDetection(j)) {
            accs[k].AddDetectionTermIn(s, tp, overlap, cell);
          }
        }
      });
}

template <typename Keeps>
void ScoreMetricsAccumulator::AddKept(const EvalFrame& frame, const ClassFrame& cf,
                                      const FrameAssociation& a, Difficulty difficulty,
                                      const Keeps& keeps, const DeceCell* dece_cells) {
  ForEachBrierTerm(
      cf, a, difficulty, transform_, keeps,
      [&](double term, int i, int j) {
        AddLabelTerm(term);
        if (j < 0) return;  // a label alone: no localization error
        const Object& label = frame.labels[cf.label_object[i]];
        const Object& det = frame.detections[cf.det_object[j]];
        const double z = label.box3d.location.z();
        if (label.Has3D() && det.Has3D() && z >= 0 && z < max_distance_m_) {
          const int bin = std::min(static_cast<int>(z / distance_bin_m_),
                                   static_cast<int>(centre_errors_.size()) - 1);
          centre_errors_[bin].push_back((det.box3d.Centre() - label.box3d.Centre()).norm());
          depth_errors_[bin].push_back(det.box3d.location.z() - z);
        }
      },
      [&](double s, Outcome o, int j) {
        const bool tp = o == Outcome::kTp;
        AddDetectionTermIn(s, tp, tp ? TpOverlap(cf, a, j) : 0.0,
                           DeceCellOf(frame, cf, j, s, dece_cells));
      });
}

void ScoreMetricsAccumulator::EnableDece(const DeceOptions& options) {
  options.Check();
  dece_ = options;
  for (int d = 0; d < 5; ++d) dece_step_[d] = 1.0 / options.bins[d];
  size_t total = 1;
  for (const int b : options.bins) total *= static_cast<size_t>(b);
  dece_count_.assign(total, 0);
  dece_tp_.assign(total, 0);
  dece_score_sum_.assign(total, 0.0);
}

namespace {

// numpy.histogramdd's bin of v among `bins` equal-width bins of [0, 1] (edges as numpy.linspace
// makes them: i * (1 / bins), the last exactly 1; a value equal to an edge goes to the bin above
// it, 1 to the last bin); v in [0, 1] (netcal clamps every feature into it first); `step` is
// 1.0 / bins.
int EqualWidthBin(double v, int bins, double step) {
  if (v >= 1.0) return bins - 1;
  int k = std::min(static_cast<int>(v * bins), bins - 1);
  // v * bins can land one bin off the edges' own rounding: settle against the edges themselves.
  while (k > 0 && v < k * step) --k;
  while (k + 1 < bins && v >= (k + 1) * step) ++k;
  return k;
}

}  // namespace

void ScoreMetricsAccumulator::AddLabelTerm(double term) {
  brier_sums_.over_labels += term;
  brier_sums_.over_all += term;
  ++brier_sums_.num_label_terms;
  ++brier_sums_.num_all_terms;
}

void ScoreMetricsAccumulator::AddDetectionTerm(double s, bool tp, double overlap,
                                               const Box2D* box) {
  AddDetectionTermIn(s, tp, overlap, DeceCellOf(s, box));
}

ScoreMetricsAccumulator::DeceCell ScoreMetricsAccumulator::DeceCellOf(double s,
                                                                      const Box2D* box) const {
  DeceCell cell;
  if (dece_count_.empty()) return cell;
  if (box == nullptr) {
    cell.state = DeceCell::kNoBox;
    return cell;
  }
  const double w = dece_.image_width_px, h = dece_.image_height_px;
  const double features[5] = {s, (box->left + box->right) / 2 / w, (box->top + box->bottom) / 2 / h,
                              (box->right - box->left) / w, (box->bottom - box->top) / h};
  // As netcal: every feature clamped into [0, 1], so that a box reaching past the image (a
  // truncated object) counts in the edge bins.
  cell.state = DeceCell::kIn;
  for (int d = 0; d < 5; ++d) {
    cell.outside = cell.outside || !(features[d] >= 0.0 && features[d] <= 1.0);
    const double v = std::isnan(features[d]) ? 0.0 : std::clamp(features[d], 0.0, 1.0);
    cell.index = cell.index * static_cast<size_t>(dece_.bins[d]) +
                 static_cast<size_t>(EqualWidthBin(v, dece_.bins[d], dece_step_[d]));
  }
  return cell;
}

void ScoreMetricsAccumulator::AddDetectionTermIn(double s, bool tp, double overlap,
                                                 const DeceCell& cell) {
  if (cell.state == DeceCell::kNoBox) {
    boxes_known_ = false;
  } else if (cell.state == DeceCell::kIn) {
    ++dece_count_[cell.index];
    dece_tp_[cell.index] += tp ? 1 : 0;
    dece_score_sum_[cell.index] += std::clamp(s, 0.0, 1.0);
    dece_outside_ += cell.outside ? 1 : 0;
  }
  const int num_bins = static_cast<int>(bin_count_.size());
  const double y = tp ? 1.0 : 0.0;
  brier_sums_.over_detections += (s - y) * (s - y);
  ++brier_sums_.num_detection_terms;
  if (!tp) {
    brier_sums_.over_all += s * s;
    ++brier_sums_.num_all_terms;
  }
  if (s < 0 || s > 1) ++out_of_range_;
  const double clamped = std::clamp(s, 0.0, 1.0);
  const int bin = std::min(static_cast<int>(clamped * num_bins), num_bins - 1);
  ++bin_count_[bin];
  bin_tp_[bin] += tp ? 1 : 0;
  bin_score_sum_[bin] += s;
  if (tp) {
    overlaps_known_ = overlaps_known_ && !std::isnan(overlap);
    bin_iou_sum_[bin] += overlap;
  }
}

BrierScores ScoreMetricsAccumulator::Brier() const {
  BrierScores b = brier_sums_;
  auto mean = [](double sum, int64_t n) { return n > 0 ? sum / static_cast<double>(n) : kNaN; };
  b.over_labels = mean(b.over_labels, b.num_label_terms);
  b.over_detections = mean(b.over_detections, b.num_detection_terms);
  b.over_all = mean(b.over_all, b.num_all_terms);
  return b;
}

CalibrationResult ScoreMetricsAccumulator::Calibration() const {
  CalibrationResult c;
  const int num_bins = static_cast<int>(bin_count_.size());
  for (int k = 0; k < num_bins; ++k) c.num_detections += bin_count_[k];
  c.num_out_of_range = out_of_range_;
  double ece = 0.0, laece = 0.0;
  for (int k = 0; k < num_bins; ++k) {
    ReliabilityBin bin;
    bin.lower = static_cast<double>(k) / num_bins;
    bin.upper = static_cast<double>(k + 1) / num_bins;
    bin.count = bin_count_[k];
    if (bin.count > 0) {
      bin.mean_score = bin_score_sum_[k] / static_cast<double>(bin.count);
      bin.tp_fraction = static_cast<double>(bin_tp_[k]) / static_cast<double>(bin.count);
      bin.mean_iou = overlaps_known_ ? bin_iou_sum_[k] / static_cast<double>(bin.count) : kNaN;
      const double weight = static_cast<double>(bin.count) / static_cast<double>(c.num_detections);
      ece += weight * std::abs(bin.mean_score - bin.tp_fraction);
      laece += weight * std::abs(bin.mean_score - bin.mean_iou);
    } else {
      bin.mean_score = bin.tp_fraction = bin.mean_iou = kNaN;
    }
    c.bins.push_back(bin);
  }
  c.ece = c.num_detections > 0 ? ece : kNaN;
  c.laece = c.num_detections > 0 && overlaps_known_ ? laece : kNaN;
  c.dece = kNaN;
  c.dece_outside = dece_outside_;
  if (!dece_count_.empty() && boxes_known_) {
    int64_t n = 0;
    for (const int64_t count : dece_count_) n += count;
    double dece = 0.0;
    for (size_t k = 0; k < dece_count_.size(); ++k) {
      if (dece_count_[k] == 0) continue;
      const double count = static_cast<double>(dece_count_[k]);
      dece += count / static_cast<double>(n) *
              std::abs(static_cast<double>(dece_tp_[k]) / count - dece_score_sum_[k] / count);
    }
    if (n > 0) c.dece = dece;
  }
  return c;
}

std::vector<DistanceBin> ScoreMetricsAccumulator::Localization() const {
  std::vector<DistanceBin> bins;
  for (size_t k = 0; k < centre_errors_.size(); ++k) {
    DistanceBin bin;
    bin.lower_m = static_cast<double>(k) * distance_bin_m_;
    bin.upper_m = std::min(max_distance_m_, static_cast<double>(k + 1) * distance_bin_m_);
    const std::vector<double>& centre = centre_errors_[k];
    const std::vector<double>& depth = depth_errors_[k];
    bin.count = static_cast<int64_t>(centre.size());
    std::vector<double> abs_depth(depth.size());
    double sum_c = 0, sum_d = 0, sum_ad = 0;
    for (size_t i = 0; i < centre.size(); ++i) {
      sum_c += centre[i];
      sum_d += depth[i];
      abs_depth[i] = std::abs(depth[i]);
      sum_ad += abs_depth[i];
    }
    const double n = static_cast<double>(bin.count);
    bin.centre_error_mean_m = bin.count ? sum_c / n : kNaN;
    bin.depth_error_mean_m = bin.count ? sum_d / n : kNaN;
    bin.abs_depth_error_mean_m = bin.count ? sum_ad / n : kNaN;
    bin.centre_error_median_m = Quantile(centre, 0.5);
    bin.centre_error_p90_m = Quantile(centre, 0.9);
    bin.abs_depth_error_median_m = Quantile(abs_depth, 0.5);
    bin.abs_depth_error_p90_m = Quantile(abs_depth, 0.9);
    bins.push_back(bin);
  }
  return bins;
}

}  // namespace stereodet
