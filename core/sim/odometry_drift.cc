#include "core/sim/odometry_drift.h"

#include <cmath>

#include "core/localmap/pose_ops.h"

namespace lmd {

Pose2 DriftedOdometry(const Pose2& from_frame, const Pose2& to_frame, double travel_m, const OdometryDrift& drift,
                      std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Pose2 truth = Compose(Inverse(to_frame), from_frame);
  const double travel = std::abs(travel_m);
  const double heading_error = u(rng) * drift.heading_rad_per_m * travel;
  const double scale = 1.0 + u(rng) * drift.scale;
  const double c = std::cos(heading_error / 2), s = std::sin(heading_error / 2);
  return {scale * (c * truth.x - s * truth.y), scale * (s * truth.x + c * truth.y), truth.theta + heading_error};
}

double DriftRadius(double travel_m, const OdometryDrift& drift) {
  const double travel = std::abs(travel_m);
  return 0.3 + drift.scale * travel + travel * drift.heading_rad_per_m * travel / 2;
}

}  // namespace lmd
