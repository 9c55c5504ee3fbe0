#include "core/sim/pose_noise.h"

#include <cmath>

namespace lmd {

Pose2 PerturbedPose(const Pose2& truth, const PoseNoise& noise, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double distance = noise.min_off_m + (noise.max_off_m - noise.min_off_m) * u(rng);
  const double direction = 2 * M_PI * u(rng);
  const double turn_deg = noise.min_turn_deg + (noise.max_turn_deg - noise.min_turn_deg) * u(rng);
  const double sign = u(rng) < 0.5 ? -1.0 : 1.0;
  return {truth.x + distance * std::cos(direction), truth.y + distance * std::sin(direction),
          truth.theta + sign * turn_deg * M_PI / 180.0};
}

}  // namespace lmd
