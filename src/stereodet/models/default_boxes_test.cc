#include "stereodet/models/default_boxes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace stereodet {
namespace {

TEST(DefaultBoxesTest, FeatureMapSizesHalveRoundingUp) {
  DefaultBoxOptions options;  // 621 x 188
  const std::vector<FeatureMapSize> sizes = FeatureMapSizes(options);
  ASSERT_EQ(sizes.size(), 4u);
  // 621 -> 311 -> 156 -> 78 -> 39 -> 20 -> 10;  188 -> 94 -> 47 -> 24 -> 12 -> 6 -> 3
  EXPECT_EQ(sizes[0].width, 78);
  EXPECT_EQ(sizes[0].height, 24);
  EXPECT_EQ(sizes[1].width, 39);
  EXPECT_EQ(sizes[1].height, 12);
  EXPECT_EQ(sizes[2].width, 20);
  EXPECT_EQ(sizes[2].height, 6);
  EXPECT_EQ(sizes[3].width, 10);
  EXPECT_EQ(sizes[3].height, 3);
}

TEST(DefaultBoxesTest, HandCheckedTinyLayout) {
  // 64 x 32 input, stride-8 first map: 8 x 4 cells, then 4 x 2. Two ratios, so 4 boxes a cell.
  DefaultBoxOptions options;
  options.input_width = 64;
  options.input_height = 32;
  options.num_maps = 2;
  options.min_size_fraction = 0.25;  // 8 px on map 1, 16 px on map 2
  options.aspect_ratios = {1.0, 4.0};
  const std::vector<DefaultBox> boxes = GenerateDefaultBoxes(options);
  ASSERT_EQ(boxes.size(), static_cast<size_t>((8 * 4 + 4 * 2) * 4));
  // First cell: centre (4, 4); sizes 8 and 8*sqrt(2); ratio 1 -> square, ratio 4 -> w = 2h.
  EXPECT_FLOAT_EQ(boxes[0].cx, 4.0f);
  EXPECT_FLOAT_EQ(boxes[0].cy, 4.0f);
  EXPECT_FLOAT_EQ(boxes[0].w, 8.0f);
  EXPECT_FLOAT_EQ(boxes[0].h, 8.0f);
  EXPECT_FLOAT_EQ(boxes[1].w, 16.0f);
  EXPECT_FLOAT_EQ(boxes[1].h, 4.0f);
  EXPECT_FLOAT_EQ(boxes[2].w, static_cast<float>(8 * std::sqrt(2.0)));
  EXPECT_FLOAT_EQ(boxes[3].w, static_cast<float>(16 * std::sqrt(2.0)));
  EXPECT_FLOAT_EQ(boxes[3].h, static_cast<float>(4 * std::sqrt(2.0)));
  // Next cell to the right: x + 8.
  EXPECT_FLOAT_EQ(boxes[4].cx, 12.0f);
  EXPECT_FLOAT_EQ(boxes[4].cy, 4.0f);
  // First cell of row 2.
  EXPECT_FLOAT_EQ(boxes[8 * 4].cx, 4.0f);
  EXPECT_FLOAT_EQ(boxes[8 * 4].cy, 12.0f);
  // First box of map 2: centre (8, 8), size 16.
  const DefaultBox& second = boxes[8 * 4 * 4];
  EXPECT_FLOAT_EQ(second.cx, 8.0f);
  EXPECT_FLOAT_EQ(second.cy, 8.0f);
  EXPECT_FLOAT_EQ(second.w, 16.0f);
  // Last box: map 2's last cell (3, 1): centre (56, 24).
  EXPECT_FLOAT_EQ(boxes.back().cx, 56.0f);
  EXPECT_FLOAT_EQ(boxes.back().cy, 24.0f);
}

TEST(DefaultBoxesTest, CentresSpanTheImageWhenSizesRoundUp) {
  DefaultBoxOptions options;
  options.input_width = 621;  // map 1 has 78 cells over 621 px
  for (const DefaultBox& box : GenerateDefaultBoxes(options)) {
    EXPECT_GT(box.cx, 0.0f);
    EXPECT_LT(box.cx, 621.0f);
    EXPECT_GT(box.cy, 0.0f);
    EXPECT_LT(box.cy, 188.0f);
  }
}

TEST(DefaultBoxesTest, RejectsBadOptions) {
  DefaultBoxOptions options;
  options.aspect_ratios = {};
  EXPECT_THROW(GenerateDefaultBoxes(options), std::invalid_argument);
  options = {};
  options.aspect_ratios = {-1.0};
  EXPECT_THROW(GenerateDefaultBoxes(options), std::invalid_argument);
  options = {};
  options.input_width = 4;
  EXPECT_THROW(GenerateDefaultBoxes(options), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
