#include <gtest/gtest.h>

#include "stereodet/eval/bipartite_internal.h"

namespace stereodet {
namespace {

TEST(BipartiteTest, IncrementalMatchingRemovingAMatchedLabelReroutes) {
  // det 0 - {label 0, label 1}, det 1 - {label 0}.
  DetAdjacency adj;
  adj.num_labels = 2;
  adj.begin = {0, 2, 3};
  adj.labels = {0, 1, 0};
  IncrementalMatching m(&adj);
  EXPECT_TRUE(m.AddDet(0));  // det 0 - label 0
  EXPECT_TRUE(m.AddDet(1));  // det 1 - label 0, det 0 rerouted to label 1
  EXPECT_EQ(m.size(), 2);
  EXPECT_EQ(m.RemoveLabel(0), -1);
  EXPECT_EQ(m.size(), 1);
  EXPECT_EQ(m.RemoveLabel(1), -1);
  EXPECT_EQ(m.size(), 0);
}

}  // namespace
}  // namespace stereodet
