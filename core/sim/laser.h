// A simulated 2D laser range finder.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "core/io/laser_log.h"
#include "core/sim/world.h"
#include "core/types.h"

namespace lmd {

struct LaserOptions {
  double fov_deg = 180.0;      // deg, centred on the heading
  double step_deg = 1.0;       // deg between beam centres (1 or 0.5 typical)
  double max_range = 30.0;     // m; no hit within it -> range = max_range
  double range_noise_m = 0.01; // m, standard deviation of Gaussian range noise
};

// round(fov/step) beams with centres at -fov/2 + step/2 + i*step (the FLASER
// convention for 180 deg), ranges from World::CastRay plus noise, clamped to
// [0, max_range]; a beam with no wall within max_range returns max_range.
Scan SimulateScan(const World& world, const Pose2& pose, const LaserOptions& options,
                  std::mt19937_64& rng);

// One scan per route pose, deterministic for a given seed.
LaserLog SimulateLog(const World& world, const std::vector<Pose2>& route,
                     const LaserOptions& options, uint64_t seed);

}  // namespace lmd
