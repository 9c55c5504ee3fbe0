// Deterministic random helpers for the simulator (internal): uniform numbers
// straight from std::mt19937_64 bits, so results do not depend on the
// standard library's distribution implementations.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>

namespace lmd {

// SplitMix64 finaliser: derives independent seeds, e.g. Mix(seed, index).
inline uint64_t MixSeed(uint64_t a, uint64_t b) {
  uint64_t z = a + 0x9e3779b97f4a7c15ULL * (b + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Uniform in [0, 1).
inline double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Uniform in [a, b).
inline double Uniform(std::mt19937_64& rng, double a, double b) { return a + (b - a) * Uniform01(rng); }

// Uniform integer in [a, b] (b >= a).
inline int UniformInt(std::mt19937_64& rng, int a, int b) {
  return a + static_cast<int>(rng() % static_cast<uint64_t>(b - a + 1));
}

inline bool Chance(std::mt19937_64& rng, double p) { return Uniform01(rng) < p; }

// Standard normal (Box-Muller, one value per call).
inline double Normal(std::mt19937_64& rng) {
  const double u1 = 1.0 - Uniform01(rng);  // (0, 1]
  const double u2 = Uniform01(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace lmd
