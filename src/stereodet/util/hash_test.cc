#include "stereodet/util/hash.h"

#include <gtest/gtest.h>

namespace stereodet {
namespace {

TEST(HashTest, Fnv1a64ReferenceValues) {
  // The published FNV-1a 64 test vectors.
  EXPECT_EQ(Fnv1a64(""), 0xcbf29ce484222325ULL);
  EXPECT_EQ(Fnv1a64("a"), 0xaf63dc4c8601ec8cULL);
  EXPECT_EQ(Fnv1a64("foobar"), 0x85944171f73967e8ULL);
}

TEST(HashTest, IncrementalEqualsWhole) {
  EXPECT_EQ(Fnv1a64("bar", Fnv1a64("foo")), Fnv1a64("foobar"));
}

TEST(HashTest, HexIsSixteenDigits) {
  EXPECT_EQ(HashHex(0xcbf29ce484222325ULL), "cbf29ce484222325");
  EXPECT_EQ(HashHex(1), "0000000000000001");
}

}  // namespace
}  // namespace stereodet
