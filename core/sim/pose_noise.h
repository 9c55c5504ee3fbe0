// A known pose made uncertain, as a robot's estimate of it would be: the
// priors lmd-eval served and lmd-microbench send with their queries.
#pragma once

#include <random>

#include "core/types.h"

namespace lmd {

// Off by a uniform distance in [min_off_m, max_off_m] in a uniform
// direction, and turned by a uniform angle in [min_turn_deg, max_turn_deg]
// either way; sent as a prior with this radius and heading sigma.
struct PoseNoise {
  double min_off_m = 0.0, max_off_m = 0.0;
  double min_turn_deg = 0.0, max_turn_deg = 0.0;
  double radius_m = 0.0, sigma_deg = 0.0;
};

// A robot that knows roughly where it is (lmd-eval served --mode prior).
inline constexpr PoseNoise kRoughPrior{1.0, 3.0, 10.0, 20.0, 3.5, 20.0};
// One that tracks its pose, just after a fix (--mode tracking): a tight prior.
inline constexpr PoseNoise kTrackingPrior{0.0, 0.3, 0.0, 2.0, 0.4, 3.0};

// `truth` with `noise`; draws four numbers from `rng`.
Pose2 PerturbedPose(const Pose2& truth, const PoseNoise& noise, std::mt19937_64& rng);

}  // namespace lmd
