#include "stereodet/util/shard.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace stereodet {
namespace {

TEST(ShardTest, RangesPartitionTheListInOrderAndDifferByAtMostOne) {
  for (size_t n : {0, 1, 2, 7, 10, 100, 101}) {
    for (int count = 1; count <= 12; ++count) {
      size_t next = 0, smallest = n, largest = 0;
      for (int k = 0; k < count; ++k) {
        const Shard s{k, count};
        EXPECT_EQ(s.Begin(n), next) << n << " " << k << "/" << count;
        EXPECT_LE(s.Begin(n), s.End(n));
        smallest = std::min(smallest, s.End(n) - s.Begin(n));
        largest = std::max(largest, s.End(n) - s.Begin(n));
        next = s.End(n);
      }
      EXPECT_EQ(next, n);
      EXPECT_LE(largest - smallest, 1u) << n << " " << count;
    }
  }
}

TEST(ShardTest, HandComputedRanges) {
  // 10 frames in 3 shards: 0..2, 3..5, 6..9.
  EXPECT_EQ(Shard({0, 3}).Begin(10), 0u);
  EXPECT_EQ(Shard({0, 3}).End(10), 3u);
  EXPECT_EQ(Shard({1, 3}).End(10), 6u);
  EXPECT_EQ(Shard({2, 3}).Begin(10), 6u);
  EXPECT_EQ(Shard({2, 3}).End(10), 10u);
  EXPECT_EQ(Shard().End(10), 10u);
  EXPECT_TRUE(Shard().Whole());
}

TEST(ShardTest, NameThenParseGivesTheShardBack) {
  for (const Shard s : {Shard{0, 1}, Shard{2, 3}, Shard{999999, 1000000}}) {
    const std::optional<Shard> p = ParseShard(ShardName(s));
    ASSERT_TRUE(p.has_value()) << ShardName(s);
    EXPECT_EQ(p->index, s.index);
    EXPECT_EQ(p->count, s.count);
    EXPECT_TRUE(p->named);  // a parsed shard, 0/1 included, carries a shard record
    EXPECT_TRUE(p->Recorded());
  }
  EXPECT_FALSE(Shard().Recorded());  // no --shard: a whole run, no record
  EXPECT_TRUE((Shard{1, 2}).Recorded());
  EXPECT_EQ(ShardName(Shard{1, 4}), "1/4");
}

TEST(ShardTest, ParseRefusesBadText) {
  for (const char* bad : {"", "1", "1/", "/2", "2/2", "3/2", "0/0", "-1/2", "1/-2", " 1/2", "1/2 ",
                          "a/b", "1/2/3", "0/1000001", "99999999/100000000"}) {
    EXPECT_FALSE(ParseShard(bad).has_value()) << bad;
  }
}

TEST(ShardTest, CheckNamesTheBadField) {
  EXPECT_NO_THROW(Shard({1, 2}).Check());
  EXPECT_THROW(Shard({2, 2}).Check(), std::invalid_argument);
  EXPECT_THROW(Shard({0, 0}).Check(), std::invalid_argument);
  EXPECT_THROW(Shard({-1, 2}).Check(), std::invalid_argument);
}

}  // namespace
}  // namespace stereodet
