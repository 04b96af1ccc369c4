// Internal tests of the network (includes LibTorch): the folded learned compression is exact.
#include "stereodet/models/ssd/ssd_net.h"

#include <gtest/gtest.h>

namespace stereodet::internal {
namespace {

TEST(SsdNetTest, FoldedCompressionEqualsCompressThenStem) {
  torch::manual_seed(3);
  SsdConfig config;
  config.encoding = InputEncoding::kRgbhLearned;
  config.boxes.input_width = 37;  // odd sizes: the padded border matters
  config.boxes.input_height = 21;
  config.base_channels = 4;
  SsdNet net(config);
  const torch::Tensor input = torch::rand({2, 4, 21, 37});
  // Explicitly: the 1x1 convolution (no bias) on R, G, B, concatenated with the height, then the
  // stem.
  const torch::Tensor compressed =
      torch::nn::functional::conv2d(input.narrow(1, 0, 3), net->compress().view({2, 3, 1, 1}));
  const torch::Tensor explicit_stem =
      net->stem()->forward(torch::cat({compressed, input.narrow(1, 3, 1)}, 1));
  const torch::Tensor folded = net->Stem(input);
  ASSERT_EQ(folded.sizes(), explicit_stem.sizes());
  EXPECT_TRUE(torch::allclose(folded, explicit_stem, 1e-5, 1e-6));
  // And gradients reach the compression weights.
  net->Stem(input).sum().backward();
  EXPECT_TRUE(net->compress().grad().defined());
  EXPECT_GT(net->compress().grad().abs().sum().item<float>(), 0.0f);
}

TEST(SsdNetTest, HardNegativeMiningKeepsThreeNegativesPerPositive) {
  // One image, 10 boxes: 1 positive, 1 ignored, 8 negatives with increasing background loss.
  const int64_t boxes = 10;
  torch::Tensor logits = torch::zeros({1, boxes, 2});
  for (int j = 0; j < boxes; ++j) logits[0][j][1] = 0.1 * j;  // higher j: worse background score
  const torch::Tensor labels =
      torch::tensor({1, -1, 0, 0, 0, 0, 0, 0, 0, 0}, torch::kLong).view({1, boxes});
  const torch::Tensor deltas = torch::zeros({1, boxes, 4});
  MultiBoxLossOptions options;
  options.min_negatives_per_image = 0;
  const MultiBoxLossTerms terms = MultiBoxLoss(deltas, logits, labels, deltas, options);
  // Expected: CE of the positive + the 3 hardest negatives (j = 9, 8, 7), divided by 1 positive.
  const torch::Tensor ce = -torch::log_softmax(logits[0], 1);
  const double expected = ce[0][1].item<double>() + ce[9][0].item<double>() +
                          ce[8][0].item<double>() + ce[7][0].item<double>();
  EXPECT_NEAR(terms.confidence.item<double>(), expected, 1e-5);
  EXPECT_NEAR(terms.localization.item<double>(), 0.0, 1e-12);
  EXPECT_EQ(terms.num_positive, 1);
  // The ignored box (j = 1) never counts, even if it is the hardest.
  logits[0][1][1] = 50.0;
  EXPECT_NEAR(MultiBoxLoss(deltas, logits, labels, deltas, options).confidence.item<double>(),
              expected, 1e-5);
}

}  // namespace
}  // namespace stereodet::internal
