#include "stereodet/util/malloc_tuning.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstring>
#include <memory>
#include <vector>

namespace stereodet {
namespace {

long MinorFaults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Allocates and fills three buffers of `bytes` (a frame's image, depth and points), frees them,
// `rounds` times; returns the minor page faults meanwhile.
long FaultsOfFrameBuffers(size_t bytes, int rounds) {
  const long before = MinorFaults();
  for (int round = 0; round < rounds; ++round) {
    std::vector<std::unique_ptr<char[]>> buffers;
    for (int i = 0; i < 3; ++i) {
      buffers.emplace_back(new char[bytes]);
      std::memset(buffers.back().get(), round + 1, bytes);
    }
    // Keep the writes: a byte of each is read back before it is freed.
    for (const auto& b : buffers) {
      volatile char sink = b[bytes / 2];
      (void)sink;
    }
  }
  return MinorFaults() - before;
}

TEST(MallocTuningTest, ReusedFrameBuffersAreNotFaultedInAgain) {
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer replaces malloc: glibc's mallopt has no heap to tune (it refuses), and the
  // sanitizer's own allocator decides what is faulted in (`make sanitize`).
  GTEST_SKIP() << "glibc's malloc is replaced by AddressSanitizer's";
#elif defined(__GLIBC__)
  ASSERT_TRUE(KeepLargeBuffersInHeap());
  constexpr size_t kBytes = size_t{6} << 20;  // one 1242 x 375 float RGB image is 5.6 MB
  FaultsOfFrameBuffers(kBytes, 1);            // the first round grows the heap: faults expected
  // Ten more rounds reuse those pages. With glibc's defaults the 18 MB freed at the heap's top
  // exceed its adaptive trim threshold (twice the largest block), go back to the kernel and are
  // faulted in again: 45,800 faults (measured), against 0 with the policy. The bound is one
  // buffer's 1,536 pages of 4 KiB.
  const long faults = FaultsOfFrameBuffers(kBytes, 10);
  EXPECT_LT(faults, 1536) << "frame buffers were faulted in again after being freed";
#else
  EXPECT_FALSE(KeepLargeBuffersInHeap());
#endif
}

TEST(MallocTuningTest, LimitsCoverAFullResolutionFrame) {
  // The largest per-frame buffer of synth and stereo: 1242 x 375 x 3 floats, and the points image.
  EXPECT_GT(kHeapBlockLimitBytes, size_t{1242} * 375 * 3 * sizeof(float));
  EXPECT_GE(kHeapTrimBytes, kHeapBlockLimitBytes);
}

TEST(MallocTuningTest, HugePageAdviceCoversOnlyWholeHugePages) {
  // Under two huge pages there is no aligned 2 MiB page that the range surely holds: no advice.
  std::vector<char> small(size_t{3} << 20);
  EXPECT_FALSE(AdviseHugePages(small.data(), small.size()));
  EXPECT_FALSE(AdviseHugePages(nullptr, size_t{64} << 20));
  // A large reserved vector: the advice is taken where the kernel has transparent huge pages (a
  // kernel without them refuses it), and the memory works the same either way.
  std::vector<int64_t> values;
  ReserveOnHugePages(values, size_t{3} << 20);
  EXPECT_GE(values.capacity(), size_t{3} << 20);
  for (int64_t i = 0; i < (int64_t{3} << 20); ++i) values.push_back(i * 7);
  int64_t sum = 0;
  for (const int64_t v : values) sum += v;
  const int64_t n = int64_t{3} << 20;
  EXPECT_EQ(sum, 7 * n * (n - 1) / 2);
}

}  // namespace
}  // namespace stereodet
