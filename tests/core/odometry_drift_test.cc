#include "core/sim/odometry_drift.h"

#include <cmath>

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace lmd
