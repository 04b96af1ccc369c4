// Parallel loops over frames, built on oneTBB.
#ifndef STEREODET_UTIL_PARALLEL_H_
#define STEREODET_UTIL_PARALLEL_H_

#include <cstddef>
#include <functional>

namespace stereodet {

// Calls fn(i) for every i in [0, n), on up to `num_threads` threads (0 = all hardware threads,
// 1 = serially on the calling thread, in order). Each index is handed out one at a time, so
// frames of uneven cost balance well. If calls throw, the first exception is rethrown here after
// the running calls finish; the remaining indices may be skipped.
void ParallelFor(size_t n, const std::function<void(size_t)>& fn, int num_threads = 0);

// The number of threads ParallelFor(…, num_threads) would use.
int EffectiveThreads(int num_threads);

}  // namespace stereodet

#endif  // STEREODET_UTIL_PARALLEL_H_
