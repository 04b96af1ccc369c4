// The allocator policy of the stereodet executables: large per-frame buffers are reused from the
// heap instead of being returned to the kernel and faulted in again on the next frame.
#ifndef STEREODET_UTIL_MALLOC_TUNING_H_
#define STEREODET_UTIL_MALLOC_TUNING_H_

#include <cstddef>

namespace stereodet {

// Blocks below this many bytes come from the heap rather than from their own mmap (glibc's default
// starts at 128 KiB and adapts up to 32 MiB only after such a block is freed).
inline constexpr size_t kHeapBlockLimitBytes = size_t{32} << 20;
// Free memory at the top of a heap is returned to the kernel only beyond this many bytes.
inline constexpr size_t kHeapTrimBytes = size_t{128} << 20;

// Sets the two limits above for the whole process (glibc mallopt; a no-op elsewhere). Returns
// whether both were accepted. Meant for an executable's main(), before threads start: it is a
// process-wide policy, so library code does not call it.
//
// Why: a synthetic frame allocates and frees ~20 MB of image, depth and point buffers per camera.
// With glibc's defaults those pages went back to the kernel after every frame and were faulted in
// again, zero-filled, on the next (98,000 minor faults and 20 % of `stereodet synth`'s CPU time on
// 24 frames; docs/BENCHMARKS.md). The resident size grows by at most the trim limit.
bool KeepLargeBuffersInHeap();

// Asks the kernel to back [data, data + bytes) with transparent huge pages where the machine
// allows them only on request (Linux's THP setting "madvise", Debian's default): the 2 MiB-aligned
// part of the range, nothing for a range under 4 MiB; a no-op elsewhere. Call it on memory not
// yet touched (a reserve()'d vector), so that its first touch faults 2 MiB at a time. Returns
// whether the advice was taken; either way the memory works the same.
//
// Why: on this project's VMs a 4 KiB page fault costs about 11 us; filling a 28 MB vector of
// detections took 77 ms, 29 ms with the advice (docs/BENCHMARKS.md, COCO mode).
bool AdviseHugePages(void* data, size_t bytes);

// reserve() then AdviseHugePages on the vector's storage.
template <typename Vector>
void ReserveOnHugePages(Vector& v, size_t n) {
  v.reserve(n);
  AdviseHugePages(v.data(), v.capacity() * sizeof(typename Vector::value_type));
}

}  // namespace stereodet

#endif  // STEREODET_UTIL_MALLOC_TUNING_H_
