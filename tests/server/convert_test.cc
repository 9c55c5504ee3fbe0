#include "proto/convert.h"

#include <gtest/gtest.h>

namespace lmd {
namespace {

TEST(ConvertTest, LocalMapRoundTripsThroughTheWire) {
  LocalMap map;
  map.points = {{1.5, -2.25}, {3.0, 4.0}};
  map.trajectory = {{0.0, 0.0, 0.0}, {0.5, 0.1, 0.2}};
  Scan scan;
  scan.pose = {0.5, 0.1, 0.2};
  scan.first_angle = -1.5f;
  scan.angle_step = 0.0175f;
  scan.max_range = 30.0f;
  scan.ranges = {1.0f, 2.0f, 30.0f};
  map.scans = {scan};
  map.heading_drift_rad_per_m = 0.004;

  const LocalMap back = FromProto(ToProto(map));
  ASSERT_EQ(back.points.size(), 2u);
  EXPECT_DOUBLE_EQ(back.points[0].x, 1.5);
  EXPECT_DOUBLE_EQ(back.points[1].y, 4.0);
  ASSERT_EQ(back.trajectory.size(), 2u);
  EXPECT_DOUBLE_EQ(back.trajectory[1].theta, 0.2);
  ASSERT_EQ(back.scans.size(), 1u);
  EXPECT_EQ(back.scans[0].ranges, scan.ranges);
  EXPECT_FLOAT_EQ(back.scans[0].angle_step, 0.0175f);
  EXPECT_DOUBLE_EQ(back.scans[0].pose.x, 0.5);
  EXPECT_DOUBLE_EQ(back.heading_drift_rad_per_m, 0.004);
}

}  // namespace
}  // namespace lmd
