// The two-stage detector's box arithmetic, by hand and against brute force (no LibTorch).
#include "stereodet/models/rpn/rpn_boxes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "stereodet/geometry/iou.h"
#include "stereodet/models/rpn/rpn_model.h"

namespace stereodet {
namespace {

void ExpectBox(const Box2D& a, const Box2D& b, double tol = 1e-9) {
  EXPECT_NEAR(a.left, b.left, tol);
  EXPECT_NEAR(a.top, b.top, tol);
  EXPECT_NEAR(a.right, b.right, tol);
  EXPECT_NEAR(a.bottom, b.bottom, tol);
}

TEST(RpnBoxesTest, AnchorsByHandInOutputOrder) {
  AnchorOptions options;
  options.sizes_px = {16.0};
  options.ratios = {1.0, 4.0};
  const std::vector<Box2D> anchors = GenerateRpnAnchors(2, 1, options);
  ASSERT_EQ(anchors.size(), 4u);
  // Cell (0, 0), centre (8, 8): 16 x 16, then width 16 / 2 = 8, height 16 * 2 = 32.
  ExpectBox(anchors[0], {0, 0, 16, 16});
  ExpectBox(anchors[1], {4, -8, 12, 24});
  // Cell (0, 1), centre (24, 8).
  ExpectBox(anchors[2], {16, 0, 32, 16});
  ExpectBox(anchors[3], {20, -8, 28, 24});
  // Default: 4 sizes x 3 ratios per cell, row-major cells.
  const AnchorOptions defaults;
  EXPECT_EQ(defaults.AnchorsPerCell(), 12);
  const std::vector<Box2D> all = GenerateRpnAnchors(40, 12, defaults);
  ASSERT_EQ(all.size(), 40u * 12u * 12u);
  const Box2D& last = all.back();  // row 11, column 39, size 128, ratio 2
  EXPECT_NEAR((last.left + last.right) / 2, 39.5 * 16, 1e-9);
  EXPECT_NEAR((last.top + last.bottom) / 2, 11.5 * 16, 1e-9);
  EXPECT_NEAR(last.Height() / last.Width(), 2.0, 1e-9);
  EXPECT_NEAR(std::sqrt(last.Height() * last.Width()), 128.0, 1e-9);
  EXPECT_THROW(GenerateRpnAnchors(0, 1, defaults), std::invalid_argument);
}

TEST(RpnBoxesTest, DeltasByHandAndRoundTrip) {
  const Box2D reference{0, 0, 20, 20}, box{10, 10, 30, 50};
  // Centres (10, 10) -> (20, 30); sizes 20 x 20 -> 20 x 40.
  const std::array<float, 4> d = EncodeDeltas(box, reference);
  EXPECT_FLOAT_EQ(d[0], 0.5f);
  EXPECT_FLOAT_EQ(d[1], 1.0f);
  EXPECT_FLOAT_EQ(d[2], 0.0f);
  EXPECT_FLOAT_EQ(d[3], static_cast<float>(std::log(2.0)));
  const std::array<float, 4> h = EncodeDeltas(box, reference, kHeadDeltaWeights);
  EXPECT_FLOAT_EQ(h[0], 5.0f);
  EXPECT_FLOAT_EQ(h[1], 10.0f);
  EXPECT_FLOAT_EQ(h[3], static_cast<float>(5.0 * std::log(2.0)));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-50, 50), size(1, 80);
  for (int i = 0; i < 200; ++i) {
    const double x = pos(rng), y = pos(rng), rx = pos(rng), ry = pos(rng);
    const Box2D b{x, y, x + size(rng), y + size(rng)};
    const Box2D r{rx, ry, rx + size(rng), ry + size(rng)};
    for (const DeltaWeights& w : {DeltaWeights{}, kHeadDeltaWeights}) {
      const std::array<float, 4> e = EncodeDeltas(b, r, w);
      ExpectBox(DecodeDeltas(e.data(), r, w), b, 1e-3);
    }
  }
  // Size deltas are clamped: exp() stays finite.
  const float huge[4] = {0, 0, 1e6f, 1e6f};
  const Box2D decoded = DecodeDeltas(huge, reference);
  EXPECT_TRUE(std::isfinite(decoded.Width()));
  EXPECT_NEAR(decoded.Width(), 20.0 * 1000.0 / 16.0, 1e-6);
  EXPECT_THROW(EncodeDeltas({0, 0, 0, 5}, reference), std::invalid_argument);
}

TEST(RpnBoxesTest, AnchorAssignmentByHand) {
  // Anchors: exact object (IoU 1), half-overlap (IoU 1/3), far away (0), one inside an ignore
  // region, and a second object's best (IoU 0.25 only: still claimed).
  const std::vector<Box2D> anchors = {
      {0, 0, 10, 10}, {5, 0, 15, 10}, {100, 100, 110, 110}, {200, 0, 210, 10}, {300, 0, 320, 20}};
  const std::vector<TargetBox> objects = {
      {{0, 0, 10, 10}, 1}, {{200, 0, 210, 10}, kIgnoreLabel}, {{300, 0, 310, 10}, 2}};
  std::mt19937_64 rng(1);
  const RpnAnchorTargets t = SampleAnchors(anchors, objects, {}, rng);
  ASSERT_EQ(t.labels.size(), 5u);
  EXPECT_EQ(t.labels[0], 1);
  EXPECT_EQ(t.labels[1], -1);  // IoU 1/3 in [0.3, 0.7): neither
  EXPECT_EQ(t.labels[2], 0);
  EXPECT_EQ(t.labels[3], -1);  // inside an ignore region
  EXPECT_EQ(t.labels[4], 1);   // the best anchor of object 3 (IoU 0.25)
  EXPECT_EQ(t.num_positive, 2);
  EXPECT_EQ(t.num_negative, 1);
  for (int k = 0; k < 4; ++k) EXPECT_FLOAT_EQ(t.deltas[k], 0.0f);  // exact match
  // Anchor 4 (centre 310, 10; 20 x 20) towards object 3 (centre 305, 5; 10 x 10).
  EXPECT_FLOAT_EQ(t.deltas[16], -0.25f);
  EXPECT_FLOAT_EQ(t.deltas[17], -0.25f);
  EXPECT_FLOAT_EQ(t.deltas[18], static_cast<float>(std::log(0.5)));
}

TEST(RpnBoxesTest, AnchorSamplingCountsAndSeeds) {
  AnchorOptions a;
  const std::vector<Box2D> anchors = GenerateRpnAnchors(20, 8, a);
  std::vector<TargetBox> objects;
  for (int i = 0; i < 6; ++i) objects.push_back({{20.0 + 50 * i, 30, 60.0 + 50 * i, 60}, 1});
  AnchorSamplingOptions options;
  options.samples_per_image = 16;
  options.positive_fraction = 0.25;
  std::mt19937_64 r1(7), r2(7), r3(8);
  const RpnAnchorTargets t1 = SampleAnchors(anchors, objects, options, r1);
  const RpnAnchorTargets t2 = SampleAnchors(anchors, objects, options, r2);
  const RpnAnchorTargets t3 = SampleAnchors(anchors, objects, options, r3);
  EXPECT_EQ(t1.labels, t2.labels);
  EXPECT_NE(t1.labels, t3.labels);
  EXPECT_EQ(t1.num_positive, 4);  // more positives exist than 16 * 0.25
  EXPECT_EQ(t1.num_negative, 12);
  int pos = 0, neg = 0;
  for (int8_t l : t1.labels) {
    pos += l == 1;
    neg += l == 0;
  }
  EXPECT_EQ(pos, 4);
  EXPECT_EQ(neg, 12);
  // Every sampled positive really overlaps an object by >= 0.7 or is an object's best anchor;
  // every sampled negative overlaps all by < 0.3 (brute force).
  for (size_t i = 0; i < anchors.size(); ++i) {
    double best = 0;
    for (const TargetBox& o : objects) best = std::max(best, Iou2D(anchors[i], o.box));
    if (t1.labels[i] == 0) {
      EXPECT_LT(best, 0.3);
    }
    if (t1.labels[i] == 1) {
      EXPECT_GT(best, 0.0);
    }
  }
  // No objects: only negatives, up to the sample size.
  std::mt19937_64 r4(1);
  const RpnAnchorTargets empty = SampleAnchors(anchors, {}, options, r4);
  EXPECT_EQ(empty.num_positive, 0);
  EXPECT_EQ(empty.num_negative, 16);
}

TEST(RpnBoxesTest, ProposalsAreClippedSortedAndSuppressed) {
  const std::vector<Box2D> anchors = {
      {-10, -10, 20, 20}, {0, 0, 30, 30}, {1, 1, 31, 31}, {50, 50, 60, 60}, {70, 0, 71, 1}};
  const std::vector<float> scores = {0.5f, 0.9f, 0.8f, 0.1f, 0.95f};
  const std::vector<float> deltas(anchors.size() * 4, 0.0f);
  ProposalOptions options;
  options.post_nms_top_n = 10;
  const std::vector<ScoredBox> p =
      SelectProposals(scores.data(), deltas.data(), anchors, 64, 64, options);
  // Anchor 4 is 1 px: dropped. Anchor 2 overlaps anchor 1 by 0.88 > 0.7: suppressed. Anchor 0 is
  // clipped to [0, 20]^2 and overlaps anchor 1 by 400 / 900 < 0.7: kept.
  ASSERT_EQ(p.size(), 3u);
  ExpectBox(p[0].box, {0, 0, 30, 30});
  EXPECT_FLOAT_EQ(p[0].score, 0.9f);
  ExpectBox(p[1].box, {0, 0, 20, 20});
  ExpectBox(p[2].box, {50, 50, 60, 60});
  options.post_nms_top_n = 1;
  EXPECT_EQ(SelectProposals(scores.data(), deltas.data(), anchors, 64, 64, options).size(), 1u);
  options.post_nms_top_n = 10;
  options.pre_nms_top_n = 2;  // anchors 4 and 1 only; 4 is too small
  EXPECT_EQ(SelectProposals(scores.data(), deltas.data(), anchors, 64, 64, options).size(), 1u);
}

TEST(RpnBoxesTest, RoiSamplingIncludesObjectsAndCounts) {
  const std::vector<TargetBox> objects = {{{10, 10, 50, 40}, 2},
                                          {{100, 10, 140, 40}, kIgnoreLabel}};
  std::vector<ScoredBox> proposals;
  for (int i = 0; i < 40; ++i) proposals.push_back({{4.0 * i, 50, 4.0 * i + 30, 80}, 0.5f, 0});
  proposals.push_back({{12, 10, 52, 40}, 0.9f, 0});    // foreground (IoU 0.9)
  proposals.push_back({{101, 10, 141, 40}, 0.9f, 0});  // on the ignore region: dropped
  RoiSamplingOptions options;
  options.samples_per_image = 16;
  std::mt19937_64 rng(2);
  const RoiTargets t = SampleRois(proposals, objects, options, rng);
  ASSERT_EQ(t.rois.size(), 16u);
  EXPECT_EQ(t.num_foreground, 2);  // the proposal and the object's own box
  EXPECT_EQ(t.labels[0], 2);
  EXPECT_EQ(t.labels[1], 2);
  for (size_t i = 2; i < t.rois.size(); ++i) {
    EXPECT_EQ(t.labels[i], 0);
    EXPECT_LT(Iou2D(t.rois[i], objects[1].box), 0.5);
  }
  // The object's own box as RoI has zero deltas; the shifted proposal's decode back to the object.
  for (size_t i = 0; i < 2; ++i) {
    ExpectBox(DecodeDeltas(t.deltas.data() + 4 * i, t.rois[i], kHeadDeltaWeights), objects[0].box,
              1e-4);
  }
  // The foreground share is capped.
  options.foreground_fraction = 0.0625;  // 1 of 16
  std::mt19937_64 rng2(2);
  EXPECT_EQ(SampleRois(proposals, objects, options, rng2).num_foreground, 1);
}

TEST(RpnBoxesTest, DecodeDetectionsByHand) {
  const std::vector<Box2D> rois = {{10, 10, 30, 30}, {0, 0, 2, 2}};
  // Two classes: probabilities (background, class 1, class 2) per RoI.
  const std::vector<float> probabilities = {0.1f, 0.7f, 0.2f, 0.98f, 0.01f, 0.01f};
  std::vector<float> deltas(2 * 2 * 4, 0.0f);
  deltas[4] = 10.0f;  // RoI 0, class 2: shifted by one width (weight 10)
  RpnDecodeOptions options;
  options.score_threshold = 0.15f;
  const std::vector<ScoredBox> d =
      DecodeRpnDetections(rois, probabilities.data(), deltas.data(), 2, 100, 100, options);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].label, 1);
  EXPECT_FLOAT_EQ(d[0].score, 0.7f);
  ExpectBox(d[0].box, {10, 10, 30, 30});
  EXPECT_EQ(d[1].label, 2);
  EXPECT_FLOAT_EQ(d[1].score, 0.2f);
  ExpectBox(d[1].box, {30, 10, 50, 30});
}

TEST(RpnBoxesTest, RandomSubsetIsASubset) {
  std::mt19937_64 rng(4);
  const std::vector<int> s = RandomSubset(10, 4, rng);
  ASSERT_EQ(s.size(), 4u);
  for (size_t i = 1; i < s.size(); ++i) EXPECT_LT(s[i - 1], s[i]);
  EXPECT_EQ(RandomSubset(3, 10, rng), (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(RandomSubset(0, 5, rng).empty());
}

TEST(RpnModelConfigTest, JsonRoundTripAndNames) {
  for (RpnInput input : {RpnInput::kRgb, RpnInput::kRgbd}) {
    EXPECT_EQ(ParseRpnInput(RpnInputName(input)), input);
  }
  EXPECT_FALSE(ParseRpnInput("rgbh").has_value());
  RpnConfig config;
  config.input = RpnInput::kRgbd;
  config.input_width = 320;
  config.image_width = 24;
  config.anchors.sizes_px = {10, 20};
  const RpnConfig back = RpnConfigFromJson(RpnConfigToJson(config), "model.json");
  EXPECT_EQ(RpnConfigToJson(back), RpnConfigToJson(config));
  EXPECT_EQ(back.input, RpnInput::kRgbd);
  EXPECT_EQ(back.image_width, 24);
  std::string bad = RpnConfigToJson(config);
  bad.replace(bad.find("320"), 3, "321");
  try {
    RpnConfigFromJson(bad, "m/model.json");
    FAIL() << "a width that is no multiple of 16 was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("m/model.json"), std::string::npos) << e.what();
  }
}

TEST(RpnModelConfigTest, EncodeInputByHand) {
  cv::Mat bgr(1, 2, CV_8UC3, cv::Scalar(0, 51, 255));  // B 0, G 51, R 255
  cv::Mat depth(1, 2, CV_16UC1), height(1, 2, CV_16UC1);
  depth.at<uint16_t>(0, 0) = 0;  // no stereo
  depth.at<uint16_t>(0, 1) = 65535;
  height.at<uint16_t>(0, 0) = 0;
  height.at<uint16_t>(0, 1) = 511;
  const PlanarImage rgb = EncodeRpnInput(bgr, {}, {}, RpnInput::kRgb);
  ASSERT_EQ(rgb.channels, 3);
  EXPECT_FLOAT_EQ(rgb.At(0, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(rgb.At(1, 0, 0), 0.2f);
  EXPECT_FLOAT_EQ(rgb.At(2, 0, 0), 0.0f);
  const PlanarImage rgbd = EncodeRpnInput(bgr, depth, height, RpnInput::kRgbd);
  ASSERT_EQ(rgbd.channels, 6);
  EXPECT_FLOAT_EQ(rgbd.At(3, 0, 0), 0.0f);
  EXPECT_FLOAT_EQ(rgbd.At(5, 0, 0), 0.0f);  // "no stereo" differs from "valid, near, ground"
  EXPECT_FLOAT_EQ(rgbd.At(3, 0, 1), 1.0f);
  EXPECT_FLOAT_EQ(rgbd.At(4, 0, 1), 1.0f);
  EXPECT_FLOAT_EQ(rgbd.At(5, 0, 1), 1.0f);
  EXPECT_THROW(EncodeRpnInput(bgr, {}, {}, RpnInput::kRgbd), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
