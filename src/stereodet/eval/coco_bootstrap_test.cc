#include "stereodet/eval/coco_bootstrap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace stereodet {
namespace {

// A random COCO-shaped set: 12 images (one without anything), 3 categories, boxes of every area
// range, crowds, jittered and spurious detections with some tied scores.
struct RandomSet {
  CocoGroundTruth gt;
  std::vector<CocoDetection> dets;
};

RandomSet MakeSet(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coord(0, 300), size(4, 160), unit(0, 1);
  RandomSet s;
  s.gt.source = "random";
  for (int64_t i = 1; i <= 12; ++i) s.gt.image_ids.push_back(10 * i);
  for (int64_t k = 1; k <= 3; ++k) s.gt.categories.push_back({k, ""});
  int64_t id = 1;
  for (int i = 0; i < 90; ++i) {
    CocoAnnotation a;
    a.id = id++;
    a.image_id = 10 * (1 + static_cast<int>(unit(rng) * 11));  // image 120 stays empty
    a.category_id = 1 + i % 3;
    a.bbox = {coord(rng), coord(rng), size(rng), size(rng)};
    a.area = a.bbox.width * a.bbox.height * (0.6 + 0.4 * unit(rng));
    a.iscrowd = i % 29 == 0;
    s.gt.annotations.push_back(a);
    // Scores on a coarse grid, so that ties happen within and across images.
    auto score = [&] { return std::round(unit(rng) * 20) / 20; };
    if (unit(rng) < 0.8) {
      s.dets.push_back(
          {a.image_id,
           a.category_id,
           {a.bbox.x + a.bbox.width * 0.3 * unit(rng), a.bbox.y, a.bbox.width, a.bbox.height},
           score()});
    }
    s.dets.push_back(
        {a.image_id, a.category_id, {coord(rng), coord(rng), size(rng), size(rng)}, score()});
  }
  return s;
}

// The data set of resample `w`: image i repeated w[i] times, copies next to each other in image
// order (ids i * 100 + copy), annotations with fresh ids, detections in file order per copy.
RandomSet Materialise(const RandomSet& s, const std::vector<int32_t>& w) {
  RandomSet m;
  m.gt.source = "materialised";
  m.gt.categories = s.gt.categories;
  int64_t id = 1;
  for (size_t i = 0; i < s.gt.image_ids.size(); ++i) {
    const int64_t image = s.gt.image_ids[i];
    for (int32_t copy = 0; copy < w[i]; ++copy) {
      const int64_t new_image = image * 100 + copy;
      m.gt.image_ids.push_back(new_image);
      for (const CocoAnnotation& a : s.gt.annotations) {
        if (a.image_id != image) continue;
        CocoAnnotation b = a;
        b.id = id++;
        b.image_id = new_image;
        m.gt.annotations.push_back(b);
      }
      for (const CocoDetection& d : s.dets) {
        if (d.image_id != image) continue;
        CocoDetection e = d;
        e.image_id = new_image;
        m.dets.push_back(e);
      }
    }
  }
  return m;
}

TEST(CocoBootstrapTest, EqualsEvaluateCocoOnMaterialisedResamples) {
  for (const CocoMatcher matcher : {CocoMatcher::kCoco, CocoMatcher::kOptimal}) {
    for (const uint32_t seed : {1u, 2u}) {
      SCOPED_TRACE(std::string(CocoMatcherName(matcher)) + " seed " + std::to_string(seed));
      const RandomSet s = MakeSet(seed);
      CocoEvalOptions options;
      options.matcher = matcher;
      options.max_dets = {1, 3, 100};  // so that max_dets cuts images with ties
      BootstrapOptions bootstrap;
      bootstrap.num_resamples = 25;
      bootstrap.seed = seed;
      bootstrap.keep_samples = true;
      CocoEvalResult evaluated;
      const CocoBootstrapResult b = BootstrapCoco(s.gt, s.dets, options, bootstrap, &evaluated);
      const CocoEvalResult direct = EvaluateCoco(s.gt, s.dets, options);
      EXPECT_EQ(evaluated.stats, direct.stats);
      int compared = 0;
      for (int r = 0; r < bootstrap.num_resamples; ++r) {
        const std::vector<int32_t> w = BootstrapFrameCounts(12, bootstrap.seed, r);
        const RandomSet m = Materialise(s, w);
        const CocoEvalResult e = EvaluateCoco(m.gt, m.dets, options);
        for (int i = 0; i < kNumCocoStats; ++i) {
          const double sample = b.stats[i].samples[r];
          if (e.stats[i] == -1) {
            EXPECT_TRUE(std::isnan(sample)) << "resample " << r << " number " << i;
          } else {
            EXPECT_EQ(sample, e.stats[i]) << "resample " << r << " number " << i;  // bit for bit
            ++compared;
          }
        }
      }
      EXPECT_GT(compared, 200);
      for (int i = 0; i < kNumCocoStats; ++i) {
        EXPECT_EQ(b.stats[i].estimate, direct.stats[i]);
        if (direct.stats[i] >= 0) {
          EXPECT_LE(b.stats[i].lower, b.stats[i].upper);
        }
      }
      EXPECT_EQ(b.num_images, 12);
      EXPECT_EQ(b.matcher, matcher);
    }
  }
}

// With score_metrics, the Brier numbers of each resample are EvaluateCoco's on the materialised
// image list (up to rounding: weighted sums), for both matchers; the ECE ones are not resampled.
TEST(CocoBootstrapTest, BrierNumbersEqualEvaluateCocoOnMaterialisedResamples) {
  for (const CocoMatcher matcher : {CocoMatcher::kCoco, CocoMatcher::kOptimal}) {
    SCOPED_TRACE(CocoMatcherName(matcher));
    const RandomSet s = MakeSet(6);
    CocoEvalOptions options;
    options.matcher = matcher;
    options.score_metrics = true;
    options.score_threshold = 0.2;
    BootstrapOptions bootstrap;
    bootstrap.num_resamples = 15;
    bootstrap.keep_samples = true;
    const CocoBootstrapResult b = BootstrapCoco(s.gt, s.dets, options, bootstrap);
    const CocoEvalResult direct = EvaluateCoco(s.gt, s.dets, options);
    int compared = 0;
    for (int i = 0; i < kNumCocoScoreStats; ++i) {
      EXPECT_EQ(b.score_stats[i].estimate, direct.score_stats[i]) << i;
    }
    for (int r = 0; r < bootstrap.num_resamples; ++r) {
      const RandomSet m = Materialise(s, BootstrapFrameCounts(12, bootstrap.seed, r));
      const CocoEvalResult e = EvaluateCoco(m.gt, m.dets, options);
      for (int i = 0; i < 9; ++i) {  // BL, BD, BA at [.50:.95], .50, .75
        const double sample = b.score_stats[i].samples[r];
        if (e.score_stats[i] == -1) {
          EXPECT_TRUE(std::isnan(sample)) << "resample " << r << " number " << i;
        } else {
          EXPECT_NEAR(sample, e.score_stats[i], 1e-12) << "resample " << r << " number " << i;
          ++compared;
        }
      }
      for (int i = 9; i < kNumCocoScoreStats; ++i) {
        EXPECT_TRUE(std::isnan(b.score_stats[i].samples[r]));
      }
    }
    EXPECT_GT(compared, 100);
    EXPECT_LE(b.score_stats[0].lower, b.score_stats[0].upper);
  }
}

TEST(CocoBootstrapTest, ThreadsDoNotChangeTheIntervals) {
  const RandomSet s = MakeSet(3);
  BootstrapOptions one, many;
  one.num_resamples = many.num_resamples = 40;
  one.num_threads = 1;
  many.num_threads = 3;
  const CocoBootstrapResult a = BootstrapCoco(s.gt, s.dets, CocoEvalOptions(), one);
  const CocoBootstrapResult b = BootstrapCoco(s.gt, s.dets, CocoEvalOptions(), many);
  for (int i = 0; i < kNumCocoStats; ++i) {
    EXPECT_EQ(a.stats[i].lower, b.stats[i].lower) << i;
    EXPECT_EQ(a.stats[i].upper, b.stats[i].upper) << i;
    EXPECT_EQ(a.stats[i].num_defined, b.stats[i].num_defined) << i;
  }
}

// A against itself: every difference exactly 0; A against a weaker B (its true detections' scores
// lowered below the spurious ones): the AP difference positive, its interval around the estimate,
// and each resample's difference the two resamples' values subtracted.
TEST(CocoBootstrapTest, PairedDifferences) {
  const RandomSet s = MakeSet(4);
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 60;
  bootstrap.keep_samples = true;
  const CocoPairedBootstrapResult same =
      PairedBootstrapCoco(s.gt, s.dets, s.dets, CocoEvalOptions(), bootstrap);
  for (int i = 0; i < kNumCocoStats; ++i) {
    if (same.a.stats[i].estimate < 0) continue;
    EXPECT_EQ(same.difference.stats[i].estimate, 0.0) << i;
    EXPECT_EQ(same.difference.stats[i].lower, 0.0) << i;
    EXPECT_EQ(same.difference.stats[i].upper, 0.0) << i;
  }
  std::vector<CocoDetection> weaker = s.dets;
  for (size_t j = 0; j < weaker.size(); ++j) {
    if (j % 2 == 0) weaker[j].score *= 0.1;  // even positions: mostly the jittered true boxes
  }
  CocoEvalResult result_a, result_b;
  const CocoPairedBootstrapResult p =
      PairedBootstrapCoco(s.gt, s.dets, weaker, CocoEvalOptions(), bootstrap, &result_a, &result_b);
  // The evaluations handed over are EvaluateCoco's.
  EXPECT_EQ(result_a.stats, EvaluateCoco(s.gt, s.dets, CocoEvalOptions()).stats);
  EXPECT_EQ(result_b.precision, EvaluateCoco(s.gt, weaker, CocoEvalOptions()).precision);
  const BootstrapInterval& ap = p.difference.stats[0];
  EXPECT_EQ(ap.estimate, p.a.stats[0].estimate - p.b.stats[0].estimate);
  EXPECT_GT(ap.estimate, 0);
  EXPECT_LE(ap.lower, ap.estimate);
  EXPECT_GE(ap.upper, ap.estimate);
  for (int r = 0; r < bootstrap.num_resamples; ++r) {
    EXPECT_EQ(ap.samples[r], p.a.stats[0].samples[r] - p.b.stats[0].samples[r]);
  }
  // The single-set results of a paired run are BootstrapCoco's.
  const CocoBootstrapResult alone = BootstrapCoco(s.gt, weaker, CocoEvalOptions(), bootstrap);
  EXPECT_EQ(alone.stats[0].samples, p.b.stats[0].samples);
}

// BCa: the same resamples as the percentile method, other bounds around the estimate; A against
// itself still exactly 0 (every resample ties the estimate: z0 = 0, a = 0).
TEST(CocoBootstrapTest, BcaIntervals) {
  const RandomSet s = MakeSet(5);
  BootstrapOptions bootstrap;
  bootstrap.num_resamples = 80;
  bootstrap.keep_samples = true;
  const CocoBootstrapResult percentile = BootstrapCoco(s.gt, s.dets, CocoEvalOptions(), bootstrap);
  bootstrap.method = BootstrapMethod::kBca;
  bootstrap.jackknife_groups = 6;
  const CocoBootstrapResult bca = BootstrapCoco(s.gt, s.dets, CocoEvalOptions(), bootstrap);
  EXPECT_EQ(bca.method, BootstrapMethod::kBca);
  for (int i = 0; i < kNumCocoStats; ++i) {
    EXPECT_EQ(bca.stats[i].estimate, percentile.stats[i].estimate);
    ASSERT_EQ(bca.stats[i].samples.size(), percentile.stats[i].samples.size());
    for (size_t r = 0; r < bca.stats[i].samples.size(); ++r) {
      const double a = bca.stats[i].samples[r], b = percentile.stats[i].samples[r];
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b)));
    }
  }
  const BootstrapInterval& ap = bca.stats[0];
  ASSERT_FALSE(std::isnan(ap.lower));
  EXPECT_LE(ap.lower, ap.estimate);
  EXPECT_GE(ap.upper, ap.estimate);
  EXPECT_FALSE(std::isnan(ap.acceleration));
  const CocoPairedBootstrapResult same =
      PairedBootstrapCoco(s.gt, s.dets, s.dets, CocoEvalOptions(), bootstrap);
  EXPECT_EQ(same.difference.stats[0].lower, 0.0);
  EXPECT_EQ(same.difference.stats[0].upper, 0.0);
  EXPECT_EQ(same.difference.stats[0].bias_correction, 0.0);
}

}  // namespace
}  // namespace stereodet
