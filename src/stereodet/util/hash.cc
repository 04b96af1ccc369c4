#include "stereodet/util/hash.h"

#include <fmt/format.h>

namespace stereodet {

uint64_t Fnv1a64(std::string_view data, uint64_t hash) {
  constexpr uint64_t kPrime = 1099511628211ULL;
  for (const char c : data) {
    hash ^= static_cast<unsigned char>(c);
    hash *= kPrime;
  }
  return hash;
}

std::string HashHex(uint64_t hash) { return fmt::format("{:016x}", hash); }

}  // namespace stereodet
