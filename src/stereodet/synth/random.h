// Deterministic random numbers for scene sampling and sensor noise.
//
// Everything random in a synthetic frame comes from generators seeded by (dataset seed, frame
// index, stream), never from shared state, so a frame's bytes do not depend on which thread made it
// or in which order. The generator and the distributions are written here (not std::mt19937 with
// std::normal_distribution, whose outputs the C++ standard leaves to the library), so the same seed
// gives the same data set with any standard library.
#ifndef STEREODET_SYNTH_RANDOM_H_
#define STEREODET_SYNTH_RANDOM_H_

#include <cmath>
#include <cstdint>
#include <initializer_list>

namespace stereodet {

// SplitMix64's finaliser: a strong 64-bit mixing function (bijective).
inline uint64_t Mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Hash of a sequence of integers, e.g. HashOf({seed, frame, kStreamLidar}).
inline uint64_t HashOf(std::initializer_list<uint64_t> values) {
  uint64_t h = 0x6a09e667f3bcc909ULL;
  for (uint64_t v : values) h = Mix64(h ^ Mix64(v));
  return h;
}

// Uniform in [0, 1) from the top 24 bits of a hash (float precision).
inline float HashToUnitFloat(uint64_t hash) {
  return static_cast<float>(hash >> 40) * (1.0f / 16777216.0f);
}

// xoshiro256** seeded through SplitMix64. Small, fast, and good enough for sampling scenes.
class Rng {
 public:
  explicit Rng(uint64_t seed) {
    for (uint64_t& s : state_) {
      seed += 0x9e3779b97f4a7c15ULL;
      s = Mix64(seed);
    }
  }

  uint64_t Next() {
    const uint64_t result = Rotl(state_[1] * 5, 7) * 9;
    const uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = Rotl(state_[3], 45);
    return result;
  }

  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [lo, hi] (inclusive). Requires lo <= hi.
  int UniformInt(int lo, int hi) {
    const uint64_t span = static_cast<uint64_t>(static_cast<int64_t>(hi) - lo + 1);
    return lo + static_cast<int>(Next() % span);
  }
  bool Bernoulli(double p) { return Uniform() < p; }
  // Normal(mean, sd) by the Box-Muller transform (one of the pair is discarded: simple, stateless).
  double Normal(double mean, double sd) {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return mean + sd * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  // Normal(mean, sd) clamped to [lo, hi].
  double ClampedNormal(double mean, double sd, double lo, double hi) {
    const double x = Normal(mean, sd);
    return x < lo ? lo : (x > hi ? hi : x);
  }
  // Index i with probability weights[i] / sum(weights). Requires a positive sum.
  int Categorical(std::initializer_list<double> weights) {
    double total = 0.0;
    for (double w : weights) total += w;
    double u = Uniform() * total;
    int i = 0;
    for (double w : weights) {
      if (u < w) return i;
      u -= w;
      ++i;
    }
    return i - 1;
  }

 private:
  static uint64_t Rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t state_[4];
};

}  // namespace stereodet

#endif  // STEREODET_SYNTH_RANDOM_H_
