// Content hashes for provenance records (which inputs a result was computed from). Not
// cryptographic: they tell runs apart, they do not resist tampering.
#ifndef STEREODET_UTIL_HASH_H_
#define STEREODET_UTIL_HASH_H_

#include <cstdint>
#include <string>
#include <string_view>

namespace stereodet {

// 64-bit FNV-1a, incremental: Fnv1a64(b, Fnv1a64(a)) == Fnv1a64(a + b).
inline constexpr uint64_t kFnv1a64Offset = 14695981039346656037ULL;
uint64_t Fnv1a64(std::string_view data, uint64_t hash = kFnv1a64Offset);

// 16 lower-case hex digits.
std::string HashHex(uint64_t hash);

}  // namespace stereodet

#endif  // STEREODET_UTIL_HASH_H_
