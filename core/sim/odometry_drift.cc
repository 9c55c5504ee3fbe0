#include "core/sim/odometry_drift.h"

#include <cmath>

#include "core/localmap/local_map_builder.h"
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

LocalMap WithDriftedOdometry(LocalMap map, const OdometryDrift& drift, double dedup_cell_m, std::mt19937_64& rng) {
  if (map.scans.empty()) return map;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double scale = 1.0 + u(rng) * drift.scale;
  const double heading_rad_per_m = u(rng) * drift.heading_rad_per_m;
  Pose2 previous_truth = map.scans.front().pose;
  Pose2 drifted = previous_truth;
  map.trajectory.clear();
  for (Scan& scan : map.scans) {
    const Pose2 step = Compose(Inverse(previous_truth), scan.pose);
    previous_truth = scan.pose;
    const double turn = heading_rad_per_m * std::hypot(step.x, step.y);
    // The step's heading error builds up along it: half of it turns its path.
    const double c = std::cos(turn / 2), s = std::sin(turn / 2);
    drifted = Compose(drifted, {scale * (c * step.x - s * step.y), scale * (s * step.x + c * step.y),
                                step.theta + turn});
    scan.pose = drifted;
    map.trajectory.push_back(drifted);
  }
  map.points = PointsFromScans(map.scans, dedup_cell_m);
  map.heading_drift_rad_per_m = drift.heading_rad_per_m;
  return map;
}

double DriftRadius(double travel_m, const OdometryDrift& drift) {
  const double travel = std::abs(travel_m);
  return 0.3 + drift.scale * travel + travel * drift.heading_rad_per_m * travel / 2;
}

}  // namespace lmd
