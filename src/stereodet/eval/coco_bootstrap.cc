#include "stereodet/eval/coco_bootstrap.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>

#include "stereodet/eval/coco_internal.h"
#include "stereodet/util/check.h"
#include "stereodet/util/parallel.h"
#include "stereodet/util/timer.h"

namespace stereodet {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A resample's numbers: the 12 of summarize(), then the 12 operating-point ones (score_stats; NaN
// without score_metrics, and the ECE ones always: calibration is not resampled).
constexpr int kNumNumbers = kNumCocoStats + kNumCocoScoreStats;
using Numbers = std::array<double, kNumNumbers>;

// The evaluation's own numbers (-1 where undefined, as EvaluateCoco gives them).
Numbers EstimateNumbers(const CocoEvalResult& r) {
  Numbers n;
  for (int i = 0; i < kNumCocoStats; ++i) n[i] = r.stats[i];
  for (int i = 0; i < kNumCocoScoreStats; ++i) {
    n[kNumCocoStats + i] = r.options.score_metrics ? r.score_stats[i] : kNaN;
  }
  return n;
}

// One category's detections in accumulate()'s score order, cut into blocks: maximal runs of one
// image's detections of one score. A resample repeats each block w_image times in place, which is
// the order a stable sort by score gives the materialised data set (its copies of an image lie
// next to each other, so their equal scores follow one another).
struct PreparedCategory {
  const CocoCategoryDetections* detections = nullptr;
  std::vector<uint32_t> order;        // by score, ties in concatenation order
  std::vector<uint32_t> block_begin;  // into order; one past the last block's end appended
};

// An evaluation made ready for resampling: its categories, and the (area range, max_dets) slices
// the summary reads.
struct Prepared {
  CocoEvalResult result;  // on the images as given
  std::vector<CocoCategoryDetections> categories;
  std::vector<PreparedCategory> prepared;
  std::vector<std::pair<int, int>> slices;  // (area range, max_dets), each once
};

Prepared Prepare(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                 const CocoEvalOptions& options) {
  Prepared p;
  p.result = EvaluateCocoKeepingDetections(gt, dets, options, &p.categories);
  p.prepared.resize(p.categories.size());
  for (size_t k = 0; k < p.categories.size(); ++k) {
    const CocoCategoryDetections& in = p.categories[k];
    PreparedCategory& c = p.prepared[k];
    c.detections = &in;
    c.order.resize(in.score.size());
    std::iota(c.order.begin(), c.order.end(), 0u);
    std::stable_sort(c.order.begin(), c.order.end(),
                     [&](uint32_t a, uint32_t b) { return in.score[a] > in.score[b]; });
    for (size_t j = 0; j < c.order.size(); ++j) {
      if (j == 0 || in.image[c.order[j]] != in.image[c.order[j - 1]] ||
          in.score[c.order[j]] != in.score[c.order[j - 1]]) {
        c.block_begin.push_back(static_cast<uint32_t>(j));
      }
    }
    c.block_begin.push_back(static_cast<uint32_t>(c.order.size()));
  }
  for (const CocoSummarySlice& slice : CocoSummarySlices(options)) {
    const std::pair<int, int> key = {slice.area, slice.max_dets};
    if (slice.area >= 0 && std::find(p.slices.begin(), p.slices.end(), key) == p.slices.end()) {
      p.slices.push_back(key);
    }
  }
  return p;
}

// One thread's memory: a CocoEvalResult whose arrays hold the summary's slices of the resample
// being computed (the other entries are never read).
struct ResampleScratch {
  CocoEvalResult replicate;
  std::vector<uint32_t> sequence;
  CocoCurveScratch curve;
};

ResampleScratch MakeScratch(const Prepared& p) {
  ResampleScratch s;
  CocoEvalResult& r = s.replicate;
  r.options = p.result.options;
  r.image_ids = p.result.image_ids;
  r.category_ids = p.result.category_ids;
  const size_t T = r.options.iou_thresholds.size(), R = r.options.recall_thresholds.size(),
               K = r.category_ids.size(), A = r.options.area_ranges.size(),
               M = r.options.max_dets.size();
  r.precision.assign(T * R * K * A * M, -1.0);
  r.scores.assign(T * R * K * A * M, -1.0);
  r.recall.assign(T * K * A * M, -1.0);
  return s;
}

// The Brier numbers of score_stats (BL, BD, BA at [.50:.95], .50, .75) of the resample with image
// counts `w`, into numbers[kNumCocoStats + ...]: each cell's sums weighted by the images' counts,
// then the summary's means over the categories (and thresholds) whose cell has a term, in
// SummarizeCells' order. Equal to EvaluateCoco's on the materialised image list up to rounding
// (the weighted sums add in another order).
void ResampleBrier(const Prepared& p, const std::vector<int32_t>& w, Numbers* numbers) {
  const CocoEvalOptions& o = p.result.options;
  const int T = static_cast<int>(o.iou_thresholds.size());
  const int K = static_cast<int>(p.categories.size());
  // Per (t, k): label sum / count, detection sum / count, FP square sum / count.
  struct Sums {
    double label = 0, detection = 0, fp = 0;
    int64_t labels = 0, detections = 0, fps = 0;
  };
  std::vector<Sums> sums(static_cast<size_t>(T) * K);
  for (int k = 0; k < K; ++k) {
    for (const CocoImageBrierTerms& e : p.categories[k].brier_terms) {
      const int32_t copies = w[e.image];
      if (copies == 0) continue;
      Sums& c = sums[static_cast<size_t>(e.t) * K + k];
      c.label += copies * e.label_sum;
      c.detection += copies * e.detection_sum;
      c.fp += copies * e.fp_square_sum;
      c.labels += static_cast<int64_t>(copies) * e.labels;
      c.detections += static_cast<int64_t>(copies) * e.detections;
      c.fps += static_cast<int64_t>(copies) * e.fps;
    }
  }
  AverageScoreStats(
      o.iou_thresholds, K, 3,
      [&](int metric, int t, int k) {
        const Sums& c = sums[static_cast<size_t>(t) * K + k];
        if (metric == 0) return c.labels > 0 ? c.label / c.labels : kNaN;
        if (metric == 1) return c.detections > 0 ? c.detection / c.detections : kNaN;
        return c.labels + c.fps > 0 ? (c.label + c.fp) / (c.labels + c.fps) : kNaN;
      },
      kNaN, numbers->data() + kNumCocoStats);
}

// The 12 numbers of the resample with image counts `w` (NaN where summarize() gives -1), and with
// score_metrics the Brier ones (ResampleBrier).
Numbers ResampleStats(const Prepared& p, const std::vector<int32_t>& w, ResampleScratch* s) {
  CocoEvalResult& r = s->replicate;
  const CocoEvalOptions& o = r.options;
  const int T = static_cast<int>(o.iou_thresholds.size()),
            R = static_cast<int>(o.recall_thresholds.size()),
            A = static_cast<int>(o.area_ranges.size());
  for (size_t k = 0; k < p.prepared.size(); ++k) {
    const PreparedCategory& c = p.prepared[k];
    const CocoCategoryDetections& in = *c.detections;
    const int ki = static_cast<int>(k);
    for (const auto& [a, m] : p.slices) {
      int64_t npig = 0;
      for (size_t e = 0; e < in.valid_image.size(); ++e) {
        npig += static_cast<int64_t>(w[in.valid_image[e]]) * in.valid_count[e * A + a];
      }
      if (npig == 0) {
        // -1: no ground truth to find (as accumulate() leaves it).
        for (int t = 0; t < T; ++t) {
          r.recall[r.RecallIndex(t, ki, a, m)] = -1.0;
          for (int ri = 0; ri < R; ++ri) r.precision[r.PrecisionIndex(t, ri, ki, a, m)] = -1.0;
        }
        continue;
      }
      // The resample's kept detections in score order: each block w times.
      const int max_det = o.max_dets[m];
      s->sequence.clear();
      for (size_t b = 0; b + 1 < c.block_begin.size(); ++b) {
        const uint32_t first = c.block_begin[b], last = c.block_begin[b + 1];
        const int32_t copies = w[in.image[c.order[first]]];
        for (int32_t copy = 0; copy < copies; ++copy) {
          for (uint32_t j = first; j < last; ++j) {
            if (in.rank[c.order[j]] < max_det) s->sequence.push_back(c.order[j]);
          }
        }
      }
      CocoAccumulateCurves(in, s->sequence, ki, a, m, npig, &s->curve, &r);
    }
  }
  SummarizeCoco(&r);
  Numbers numbers;
  numbers.fill(kNaN);
  for (int i = 0; i < kNumCocoStats; ++i) numbers[i] = r.stats[i] == -1.0 ? kNaN : r.stats[i];
  if (o.score_metrics && p.result.probability_metrics) ResampleBrier(p, w, &numbers);
  return numbers;
}

// Every resample's numbers of each prepared evaluation, resample r at [r]; resamples are handed
// to the threads in chunks, each chunk with one scratch per evaluation.
std::vector<std::vector<Numbers>> Resample(const std::vector<const Prepared*>& evaluations,
                                           const BootstrapOptions& bootstrap) {
  const size_t num = bootstrap.num_resamples;
  const int64_t num_images = static_cast<int64_t>(evaluations.front()->result.image_ids.size());
  std::vector<std::vector<Numbers>> out(evaluations.size(), std::vector<Numbers>(num));
  const size_t chunks =
      std::min(num, static_cast<size_t>(EffectiveThreads(bootstrap.num_threads)) * 4);
  ParallelFor(
      chunks,
      [&](size_t chunk) {
        std::vector<ResampleScratch> scratch;
        for (const Prepared* p : evaluations) scratch.push_back(MakeScratch(*p));
        for (size_t r = chunk; r < num; r += chunks) {
          const std::vector<int32_t> w =
              BootstrapFrameCounts(num_images, bootstrap.seed, static_cast<int64_t>(r));
          for (size_t e = 0; e < evaluations.size(); ++e) {
            out[e][r] = ResampleStats(*evaluations[e], w, &scratch[e]);
          }
        }
      },
      bootstrap.num_threads);
  return out;
}

// BCa's leave-one-group-out numbers of each evaluation ([evaluation][group]); empty vectors for
// the percentile method.
std::vector<std::vector<Numbers>> Jackknife(const std::vector<const Prepared*>& evaluations,
                                            const BootstrapOptions& bootstrap) {
  std::vector<std::vector<Numbers>> out(evaluations.size());
  if (bootstrap.method != BootstrapMethod::kBca) return out;
  const int64_t n = static_cast<int64_t>(evaluations.front()->result.image_ids.size());
  const int groups = JackknifeGroupCount(n, bootstrap.jackknife_groups);
  for (auto& values : out) values.resize(groups);
  ParallelFor(
      groups,
      [&](size_t g) {
        const std::vector<int32_t> w =
            JackknifeFrameCounts(n, bootstrap.jackknife_groups, static_cast<int>(g));
        for (size_t e = 0; e < evaluations.size(); ++e) {
          ResampleScratch scratch = MakeScratch(*evaluations[e]);
          out[e][g] = ResampleStats(*evaluations[e], w, &scratch);
        }
      },
      bootstrap.num_threads);
  return out;
}

CocoBootstrapResult MakeResult(const Prepared& p, const BootstrapOptions& bootstrap,
                               const Numbers& estimate, const std::vector<Numbers>& samples,
                               const std::vector<Numbers>& jackknife) {
  CocoBootstrapResult result;
  result.num_resamples = bootstrap.num_resamples;
  result.seed = bootstrap.seed;
  result.confidence = bootstrap.confidence;
  result.matcher = p.result.options.matcher;
  result.num_images = static_cast<int64_t>(p.result.image_ids.size());
  result.method = bootstrap.method;
  std::vector<double> values(samples.size()), jack(jackknife.size());
  const int count = p.result.options.score_metrics ? kNumNumbers : kNumCocoStats;
  for (int i = 0; i < count; ++i) {
    for (size_t r = 0; r < samples.size(); ++r) values[r] = samples[r][i];
    BootstrapInterval& interval =
        i < kNumCocoStats ? result.stats[i] : result.score_stats[i - kNumCocoStats];
    for (size_t g = 0; g < jackknife.size(); ++g) jack[g] = jackknife[g][i];
    // An estimate of -1 (no ground truth) has no BCa interval: NaN while the bounds are read.
    interval.estimate = estimate[i] == -1.0 ? kNaN : estimate[i];
    FillInterval(bootstrap, values, jack, &interval);
    interval.estimate = estimate[i];
  }
  return result;
}

}  // namespace

CocoBootstrapResult BootstrapCoco(const CocoGroundTruth& gt, const std::vector<CocoDetection>& dets,
                                  const CocoEvalOptions& options, const BootstrapOptions& bootstrap,
                                  CocoEvalResult* result) {
  options.Check();
  bootstrap.Check();
  const Timer timer;
  const Prepared p = Prepare(gt, dets, options);
  const auto samples = Resample({&p}, bootstrap);
  const auto jackknife = Jackknife({&p}, bootstrap);
  CocoBootstrapResult out =
      MakeResult(p, bootstrap, EstimateNumbers(p.result), samples[0], jackknife[0]);
  if (result != nullptr) {
    *result = p.result;
  }
  out.seconds = timer.ElapsedSeconds();
  return out;
}

CocoPairedBootstrapResult PairedBootstrapCoco(const CocoGroundTruth& gt,
                                              const std::vector<CocoDetection>& dets_a,
                                              const std::vector<CocoDetection>& dets_b,
                                              const CocoEvalOptions& options,
                                              const BootstrapOptions& bootstrap,
                                              CocoEvalResult* result_a, CocoEvalResult* result_b) {
  options.Check();
  bootstrap.Check();
  const Timer timer;
  const Prepared pa = Prepare(gt, dets_a, options);
  const Prepared pb = Prepare(gt, dets_b, options);
  const auto samples = Resample({&pa, &pb}, bootstrap);
  auto minus = [](const Numbers& a, const Numbers& b, double undefined) {
    Numbers d;
    for (int i = 0; i < kNumNumbers; ++i) {
      const bool defined =
          a[i] != undefined && b[i] != undefined && !std::isnan(a[i]) && !std::isnan(b[i]);
      d[i] = defined ? a[i] - b[i] : kNaN;
    }
    return d;
  };
  std::vector<Numbers> difference(samples[0].size());
  for (size_t r = 0; r < difference.size(); ++r) {
    difference[r] = minus(samples[0][r], samples[1][r], kNaN);
  }
  const auto jackknife = Jackknife({&pa, &pb}, bootstrap);
  std::vector<Numbers> jack_d(jackknife[0].size());
  for (size_t g = 0; g < jack_d.size(); ++g) {
    jack_d[g] = minus(jackknife[0][g], jackknife[1][g], kNaN);
  }
  CocoPairedBootstrapResult out;
  const Numbers estimate_a = EstimateNumbers(pa.result), estimate_b = EstimateNumbers(pb.result);
  out.a = MakeResult(pa, bootstrap, estimate_a, samples[0], jackknife[0]);
  out.b = MakeResult(pb, bootstrap, estimate_b, samples[1], jackknife[1]);
  out.difference =
      MakeResult(pa, bootstrap, minus(estimate_a, estimate_b, -1.0), difference, jack_d);
  if (result_a != nullptr) *result_a = pa.result;
  if (result_b != nullptr) *result_b = pb.result;
  const double seconds = timer.ElapsedSeconds();
  for (CocoBootstrapResult* r : {&out.a, &out.b, &out.difference}) r->seconds = seconds;
  return out;
}

}  // namespace stereodet
