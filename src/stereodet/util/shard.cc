#include "stereodet/util/shard.h"

#include <charconv>

#include "stereodet/util/check.h"

namespace stereodet {

void Shard::Check() const {
  STEREODET_CHECK(count >= 1 && count <= 1000000)
      << "shard count must be in 1..1000000, got " << count;
  STEREODET_CHECK(index >= 0 && index < count)
      << "shard index must be in 0.." << count - 1 << " (K/N counts K from 0), got " << index;
}

// floor(n * k / N) without overflow: (n / N) * k + floor((n % N) * k / N), where (n % N) * k < N^2.
namespace {
size_t Position(size_t n, int k, int count) {
  const size_t c = static_cast<size_t>(count), kk = static_cast<size_t>(k);
  return n / c * kk + n % c * kk / c;
}
}  // namespace

size_t Shard::Begin(size_t n) const { return Position(n, index, count); }
size_t Shard::End(size_t n) const { return Position(n, index + 1, count); }

std::string ShardName(const Shard& shard) {
  return std::to_string(shard.index) + "/" + std::to_string(shard.count);
}

std::optional<Shard> ParseShard(std::string_view text) {
  const size_t slash = text.find('/');
  if (slash == std::string_view::npos) return std::nullopt;
  auto parse = [](std::string_view s) -> std::optional<int> {
    if (s.empty() || s.size() > 7) return std::nullopt;
    for (char c : s) {
      if (c < '0' || c > '9') return std::nullopt;
    }
    int v = 0;
    std::from_chars(s.data(), s.data() + s.size(), v);
    return v;
  };
  const std::optional<int> k = parse(text.substr(0, slash));
  const std::optional<int> n = parse(text.substr(slash + 1));
  if (!k || !n) return std::nullopt;
  const Shard shard{*k, *n, /*named=*/true};
  if (shard.count < 1 || shard.count > 1000000 || shard.index >= shard.count) return std::nullopt;
  return shard;
}

}  // namespace stereodet
