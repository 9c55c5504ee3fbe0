#include "core/sim/odometry_drift.h"

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

TEST(OdometryDriftTest, WithoutDriftItIsTheTrueRelativePose) {
  const Pose2 from{1.0, 2.0, 0.3}, to{4.0, -1.0, 1.2};
  std::mt19937_64 rng(1);
  const Pose2 odometry = DriftedOdometry(from, to, 5.0, OdometryDrift{0.0, 0.0}, rng);
  const Pose2 truth = Compose(Inverse(to), from);
  EXPECT_NEAR(odometry.x, truth.x, 1e-12);
  EXPECT_NEAR(odometry.y, truth.y, 1e-12);
  EXPECT_NEAR(odometry.theta, truth.theta, 1e-12);
}

// The drifted pose stays within the radius DriftRadius gives, and its
// heading within the per-metre bound, over many draws.
TEST(OdometryDriftTest, TheDriftStaysWithinItsStatedBounds) {
  const OdometryDrift drift;
  std::mt19937_64 rng(7);
  for (double travel : {1.0, 5.0, 15.0}) {
    const Pose2 from{0, 0, 0}, to{travel, 0, 0};  // driven straight ahead
    const Pose2 truth = Compose(Inverse(to), from);
    double worst_m = 0, worst_rad = 0;
    for (int i = 0; i < 500; ++i) {
      const Pose2 o = DriftedOdometry(from, to, travel, drift, rng);
      worst_m = std::max(worst_m, std::hypot(o.x - truth.x, o.y - truth.y));
      worst_rad = std::max(worst_rad, std::abs(o.theta - truth.theta));
    }
    EXPECT_LE(worst_m, DriftRadius(travel, drift)) << travel;
    EXPECT_LE(worst_rad, drift.heading_rad_per_m * travel + 1e-12) << travel;
    EXPECT_GT(worst_rad, 0.5 * drift.heading_rad_per_m * travel) << travel;  // it does drift
  }
  EXPECT_LT(DriftRadius(1.0, drift), DriftRadius(10.0, drift));
}

// A robot drives 5 m straight along x in 0.1 m steps past a wall 2 m to its
// right, one beam straight down at it per scan: the map of a corridor.
LocalMap CorridorMap() {
  LocalMap map;
  for (int i = 0; i <= 50; ++i) {
    Scan scan;
    scan.pose = {0.1 * i, 0.0, 0.0};
    scan.first_angle = static_cast<float>(-M_PI / 2);
    scan.max_range = 30.0f;
    scan.ranges = {2.0f};
    map.trajectory.push_back(scan.pose);
    map.scans.push_back(scan);
  }
  map.points = PointsFromScans(map.scans);
  return map;
}

TEST(OdometryDriftTest, AMapOnDriftingOdometryBendsFromItsExactFirstPose) {
  const LocalMap truth = CorridorMap();
  std::mt19937_64 rng(3);
  const LocalMap same = WithDriftedOdometry(truth, OdometryDrift{0.0, 0.0}, 0.1, rng);
  ASSERT_EQ(same.points.size(), truth.points.size());
  for (size_t i = 0; i < same.points.size(); ++i) EXPECT_NEAR(same.points[i].y, truth.points[i].y, 1e-9);

  const OdometryDrift drift{0.02, 2.0 * M_PI / 180};  // up to 2 deg per metre
  double largest_turn = 0;
  for (int draw = 0; draw < 20; ++draw) {
    const LocalMap bent = WithDriftedOdometry(truth, drift, 0.1, rng);
    ASSERT_EQ(bent.trajectory.size(), truth.trajectory.size());
    EXPECT_EQ(bent.trajectory.front().x, 0.0);
    EXPECT_EQ(bent.trajectory.front().theta, 0.0);
    EXPECT_EQ(bent.heading_drift_rad_per_m, drift.heading_rad_per_m);  // as a robot that knows its odometry states it
    // One heading rate for the whole map: the last pose has turned by it
    // times the 5 m driven, and every scan sits on the drifted path.
    const double turn = bent.trajectory.back().theta;
    EXPECT_LE(std::abs(turn), drift.heading_rad_per_m * 5.0 + 1e-9);
    largest_turn = std::max(largest_turn, std::abs(turn));
    for (size_t i = 0; i < bent.scans.size(); ++i) EXPECT_EQ(bent.scans[i].pose.theta, bent.trajectory[i].theta);
    EXPECT_NEAR(std::hypot(bent.trajectory.back().x, bent.trajectory.back().y), 5.0, 5.0 * drift.scale + 1e-9);
    // The straight wall is now an arc: its far end off y = -2 by about
    // the turn's sweep (half the turn over the 5 m).
    double wall_off = 0;
    for (const Point2& p : bent.points) wall_off = std::max(wall_off, std::abs(p.y + 2.0));
    EXPECT_GT(wall_off, 0.4 * std::abs(turn) * 5.0 / 2) << turn;
  }
  EXPECT_GT(largest_turn, 0.5 * drift.heading_rad_per_m * 5.0);  // it does drift

  LocalMap no_scans = truth;
  no_scans.scans.clear();
  const LocalMap as_is = WithDriftedOdometry(no_scans, drift, 0.1, rng);
  EXPECT_EQ(as_is.trajectory.back().theta, 0.0);
}

}  // namespace
}  // namespace lmd
