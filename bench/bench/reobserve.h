// A stored map seen again, for benchmarks that need a query lmdd has not
// stored: its own frame moved by a random rigid motion (so that nothing may
// depend on it), Gaussian noise on points and ranges, a share of the points
// dropped. Truth follows the moved frame, so that PlaceOverlap and the true
// pose stay right.
#pragma once

#include <cstdint>

#include "core/types.h"

namespace lmd::bench {

LocalMap Reobserve(const LocalMap& map, uint64_t seed, double noise_m, double drop);

}  // namespace lmd::bench
