#include "stereodet/util/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "stereodet/util/check.h"

namespace stereodet {

int EffectiveThreads(int num_threads) {
  STEREODET_CHECK(num_threads >= 0)
      << "num_threads must be >= 0 (0 = all cores), got " << num_threads;
  return num_threads == 0 ? tbb::info::default_concurrency() : num_threads;
}

void ParallelFor(size_t n, const std::function<void(size_t)>& fn, int num_threads) {
  const int threads = EffectiveThreads(num_threads);
  if (threads == 1 || n <= 1) {
    for (size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  tbb::task_arena arena(threads);
  arena.execute([&] {
    // Grain size 1 with the simple partitioner: one frame per task, which balances frames of very
    // different cost; per-frame work dwarfs the scheduling overhead.
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 1),
        [&](const tbb::blocked_range<size_t>& range) {
          for (size_t i = range.begin(); i != range.end(); ++i) fn(i);
        },
        tbb::simple_partitioner());
  });
}

}  // namespace stereodet
