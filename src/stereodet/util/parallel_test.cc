#include "stereodet/util/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <vector>

namespace stereodet {
namespace {

TEST(ParallelForTest, VisitsEveryIndexExactlyOnce) {
  for (int threads : {0, 1, 2, 3}) {
    std::vector<std::atomic<int>> visits(1000);
    ParallelFor(
        visits.size(), [&](size_t i) { visits[i]++; }, threads);
    for (size_t i = 0; i < visits.size(); ++i)
      ASSERT_EQ(visits[i].load(), 1) << i << " " << threads;
  }
}

TEST(ParallelForTest, OneThreadRunsInOrder) {
  std::vector<size_t> order;
  ParallelFor(
      5, [&](size_t i) { order.push_back(i); }, 1);
  EXPECT_EQ(order, (std::vector<size_t>{0, 1, 2, 3, 4}));
}

TEST(ParallelForTest, RethrowsAnExceptionFromAWorker) {
  EXPECT_THROW(ParallelFor(
                   100,
                   [](size_t i) {
                     if (i == 37) throw std::runtime_error("frame 37");
                   },
                   2),
               std::runtime_error);
}

TEST(ParallelForTest, ZeroIterationsAndNegativeThreads) {
  int calls = 0;
  ParallelFor(0, [&](size_t) { ++calls; });
  EXPECT_EQ(calls, 0);
  EXPECT_THROW(ParallelFor(
                   1, [](size_t) {}, -1),
               std::invalid_argument);
  EXPECT_GE(EffectiveThreads(0), 1);
  EXPECT_EQ(EffectiveThreads(3), 3);
}

}  // namespace
}  // namespace stereodet
