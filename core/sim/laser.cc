#include "core/sim/laser.h"

#include <cmath>

#include "core/sim/sim_random.h"

namespace lmd {

Scan SimulateScan(const World& world, const Pose2& pose, const LaserOptions& options, std::mt19937_64& rng) {
  Scan scan;
  const double step = options.step_deg * M_PI / 180.0;
  const double fov = options.fov_deg * M_PI / 180.0;
  const int n = std::max(1, static_cast<int>(std::lround(options.fov_deg / options.step_deg)));
  scan.pose = pose;
  scan.first_angle = static_cast<float>(-fov / 2 + step / 2);
  scan.angle_step = static_cast<float>(step);
  scan.max_range = static_cast<float>(options.max_range);
  scan.ranges.resize(static_cast<size_t>(n));
  const Point2 origin{pose.x, pose.y};
  for (int i = 0; i < n; ++i) {
    const double a = pose.theta + static_cast<double>(scan.first_angle) + i * step;
    double r = world.CastRay(origin, a, options.max_range);
    if (r < options.max_range) {
      if (options.range_noise_m > 0) r += options.range_noise_m * Normal(rng);
      // Stays a return: just below the maximum, never negative.
      r = std::min(std::max(r, 0.0), options.max_range - 1e-3);
    }
    scan.ranges[static_cast<size_t>(i)] = static_cast<float>(r);
  }
  return scan;
}

LaserLog SimulateLog(const World& world, const std::vector<Pose2>& route, const LaserOptions& options, uint64_t seed) {
  std::mt19937_64 rng(seed);
  LaserLog log;
  log.scans.reserve(route.size());
  for (const Pose2& p : route) log.scans.push_back(SimulateScan(world, p, options, rng));
  return log;
}

}  // namespace lmd
