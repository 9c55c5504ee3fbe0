#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "core/align/icp.h"
#include "core/align/prepared_map.h"
#include "tests/core/wall_maps.h"

namespace lmd {
namespace {

using testing::CorridorWalls;
using testing::RoomWalls;

// A corridor 2 m wide along x, `half_length` m either way.
std::vector<Point2> Corridor(double half_length) { return CorridorWalls(-half_length, half_length).points; }

// A closed 4 m x 3 m room.
std::vector<Point2> Room() { return RoomWalls(4.0, 3.0).points; }

std::vector<Point2> WithNoise(std::vector<Point2> points, double sigma_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  for (Point2& p : points) p.x += noise(rng), p.y += noise(rng);
  return points;
}

double Sigma(const Eigen::Matrix3d& covariance, int axis) { return std::sqrt(covariance(axis, axis)); }

TEST(PoseCovarianceTest, ACorridorLeavesItsLengthUnknownAndItsWidthKnown) {
  const PreparedMap db = PreparePoints(Corridor(8.0));
  const std::vector<Point2> query = WithNoise(Corridor(2.0), 0.01, 1);
  const PoseCovarianceOptions options;
  const Eigen::Matrix3d c = PoseCovariance(query, db, {0, 0, 0}, {}, options);
  // Along the corridor nothing constrains the pose but the search's reach.
  EXPECT_GT(Sigma(c, 0), 0.9 * options.max_sigma_m);
  EXPECT_LE(Sigma(c, 0), std::hypot(options.max_sigma_m, options.floor_sigma_m) + 1e-9);
  // Across it and in heading, the walls do: a few centimetres and tenths of a degree.
  EXPECT_LT(Sigma(c, 1), 0.05);
  EXPECT_LT(Sigma(c, 2), 1.0 * M_PI / 180);
}

TEST(PoseCovarianceTest, AClosedRoomPinsEveryDirection) {
  const PreparedMap db = PreparePoints(Room());
  const std::vector<Point2> query = WithNoise(Room(), 0.01, 2);
  const Eigen::Matrix3d c = PoseCovariance(query, db, {0, 0, 0});
  EXPECT_LT(Sigma(c, 0), 0.05);
  EXPECT_LT(Sigma(c, 1), 0.05);
  EXPECT_LT(Sigma(c, 2), 1.0 * M_PI / 180);
  // Symmetric and positive definite: a covariance a filter can fuse.
  EXPECT_TRUE(c.isApprox(c.transpose()));
  EXPECT_EQ(Eigen::LLT<Eigen::Matrix3d>(c).info(), Eigen::Success);
}

TEST(PoseCovarianceTest, NoisierPointsGiveALargerCovarianceAboveTheFloor) {
  const PreparedMap db = PreparePoints(Room());
  PoseCovarianceOptions no_floor;
  no_floor.floor_sigma_m = no_floor.floor_sigma_rad = 0.0;
  const Eigen::Matrix3d clean = PoseCovariance(WithNoise(Room(), 0.01, 3), db, {0, 0, 0}, {}, no_floor);
  const Eigen::Matrix3d noisy = PoseCovariance(WithNoise(Room(), 0.05, 3), db, {0, 0, 0}, {}, no_floor);
  for (int axis = 0; axis < 3; ++axis) EXPECT_GT(Sigma(noisy, axis), 2 * Sigma(clean, axis)) << axis;
  // The floor is what two maps of one place differ by, however well they fit.
  const Eigen::Matrix3d floored = PoseCovariance(WithNoise(Room(), 0.01, 3), db, {0, 0, 0});
  EXPECT_GE(Sigma(floored, 0), PoseCovarianceOptions().floor_sigma_m);
  EXPECT_GE(Sigma(floored, 2), PoseCovarianceOptions().floor_sigma_rad);
}

TEST(PoseCovarianceTest, NothingToFitLeavesTheSearchsReach) {
  const PoseCovarianceOptions options;
  const PreparedMap db = PreparePoints(Room());
  // No query points, or none near the map's: the bound alone.
  for (const std::vector<Point2>& query : {std::vector<Point2>{}, std::vector<Point2>{{40, 40}, {41, 40}, {40, 41}}}) {
    const Eigen::Matrix3d c = PoseCovariance(query, db, {0, 0, 0}, {}, options);
    EXPECT_DOUBLE_EQ(Sigma(c, 0), options.max_sigma_m);
    EXPECT_DOUBLE_EQ(Sigma(c, 2), options.max_sigma_rad);
    EXPECT_TRUE(c.allFinite());
  }
}

// The position's deviation is along its least known direction, whichever
// way that lies: 8 cm along the diagonal, 1 cm across it.
TEST(PoseCovarianceTest, StandardDeviationsAreAlongTheLeastKnownDirection) {
  Eigen::Matrix3d c = Eigen::Vector3d(0.08 * 0.08, 0.01 * 0.01, 0.005 * 0.005).asDiagonal();
  Eigen::Matrix3d turn = Eigen::Matrix3d::Identity();
  turn.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(M_PI / 4).toRotationMatrix();
  c = turn * c * turn.transpose();
  EXPECT_NEAR(std::sqrt(c(0, 0)), 0.057, 0.001);  // either axis alone reads less
  const PoseDeviations sd = PoseStandardDeviations(c);
  EXPECT_NEAR(sd.position_m, 0.08, 1e-9);
  EXPECT_NEAR(sd.heading_rad, 0.005, 1e-12);
}

// A map driven 4 m (two 2 m legs at a right angle) on odometry that may
// turn it by 1 deg per metre: its end by up to 4 deg, its frame under a
// rigid fit by about 2 deg, uniform: sd 2 / sqrt(3) deg; the frame 2 m from
// the middle moves by 2 m times that. Both maps' bends add up; rigid maps
// add nothing.
TEST(PoseCovarianceTest, AMapThatMayBendAddsItsBendToThePose) {
  LocalMap map = RoomWalls(4.0, 3.0);
  map.trajectory = {{0, 0, 0}, {2, 0, 0}, {2, 2, M_PI / 2}};
  const PreparedMap rigid = PrepareMap(map);
  EXPECT_EQ(rigid.bend.heading_sd_rad, 0.0);
  map.heading_drift_rad_per_m = M_PI / 180;
  const PreparedMap bendable = PrepareMap(map);
  const double heading_sd = 2.0 / std::sqrt(3.0) * M_PI / 180;
  EXPECT_NEAR(bendable.bend.heading_sd_rad, heading_sd, 1e-12);
  EXPECT_NEAR(bendable.bend.position_sd_m, 2.0 * heading_sd, 1e-12);

  EXPECT_TRUE(BendCovariance(rigid, rigid).isZero());
  const Eigen::Matrix3d one = BendCovariance(bendable, rigid), both = BendCovariance(bendable, bendable);
  EXPECT_NEAR(Sigma(one, 2), heading_sd, 1e-12);
  EXPECT_NEAR(Sigma(one, 0), 2.0 * heading_sd, 1e-12);
  EXPECT_NEAR(Sigma(one, 1), 2.0 * heading_sd, 1e-12);
  EXPECT_NEAR(Sigma(both, 2), std::sqrt(2.0) * heading_sd, 1e-12);
  EXPECT_TRUE(BendCovariance(rigid, bendable).isApprox(one));

  // Without a trajectory, the scans' poses are the path.
  LocalMap scanned = map;
  for (const Pose2& pose : map.trajectory) scanned.scans.push_back(Scan{pose, 0.0f, 0.01f, 10.0f, {}});
  scanned.trajectory.clear();
  EXPECT_NEAR(MapBend(scanned).heading_sd_rad, heading_sd, 1e-12);
}

}  // namespace
}  // namespace lmd
