// Seeded Gaussian random numbers that are the same on every platform
// (std::normal_distribution is implementation-defined): std::mt19937_64,
// 53-bit uniforms, Box-Muller. Used for the descriptors' fixed random
// projections, which stored codes depend on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lmd {

// `count` standard normal values from `seed`.
std::vector<double> GaussianValues(uint64_t seed, size_t count);

}  // namespace lmd
