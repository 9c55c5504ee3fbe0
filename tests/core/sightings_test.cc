#include "core/change/sightings.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace lmd {
namespace {

// A 180 deg scan at (0, y) facing +x, 1 deg steps, every beam returning from
// the wall x = 5 (or from `obstacle_range` for beam `obstacle_beam`).
Scan WallScan(double y, int obstacle_beam = -1, float obstacle_range = 0.0f) {
  Scan scan;
  scan.pose = {0.0, y, 0.0};
  scan.first_angle = static_cast<float>(-M_PI / 2);
  scan.angle_step = static_cast<float>(M_PI / 180);
  scan.max_range = 30.0f;
  for (int i = 0; i <= 180; ++i) {
    const double a = scan.first_angle + i * static_cast<double>(scan.angle_step);
    const double c = std::cos(a);
    scan.ranges.push_back(i == obstacle_beam ? obstacle_range : c > 1e-6 ? static_cast<float>(5.0 / c) : 30.0f);
  }
  return scan;
}

TEST(SightingsTest, AWallReturnsEveryBeamAndFreeSpaceIsSeenThrough) {
  const std::vector<Scan> scans = {WallScan(-0.5), WallScan(0.0), WallScan(0.5)};
  const std::vector<Point2> points = {{5.0, 0.2}, {2.0, 0.1}, {7.0, 0.0}, {-3.0, 0.0}};
  const std::vector<Sightings> seen = CountSightings(points, scans);
  ASSERT_EQ(seen.size(), points.size());
  EXPECT_EQ(seen[0].returns, 3u);  // on the wall
  EXPECT_EQ(seen[0].through, 0u);
  EXPECT_EQ(seen[1].returns, 0u);  // in front of it
  EXPECT_EQ(seen[1].through, 3u);
  EXPECT_EQ(seen[2].returns + seen[2].through, 0u);  // behind it: occluded
  EXPECT_EQ(seen[3].returns + seen[3].through, 0u);  // behind the robot: out of view
}

// An object one beam wide at 3 m: the next beam passes it, but a point there
// is on the object's edge, not seen through.
TEST(SightingsTest, ABeamGrazingAnObjectsEdgeDoesNotSeeThroughIt) {
  const std::vector<Scan> scans = {WallScan(0.0, 90, 3.0f)};
  const double next = scans[0].first_angle + 91 * static_cast<double>(scans[0].angle_step);
  const double two_away = scans[0].first_angle + 92 * static_cast<double>(scans[0].angle_step);
  const std::vector<Point2> points = {
      {3.0, 0.0}, {3.0 * std::cos(next), 3.0 * std::sin(next)}, {3.0 * std::cos(two_away), 3.0 * std::sin(two_away)}};
  const std::vector<Sightings> seen = CountSightings(points, scans);
  EXPECT_EQ(seen[0].returns, 1u);
  EXPECT_EQ(seen[1].returns + seen[1].through, 0u);
  EXPECT_EQ(seen[2].through, 1u);
}

// A 360 deg scanner starting behind the robot: bearings on both sides of the
// seam find their beams.
TEST(SightingsTest, AFullTurnScannerCoversTheSeamBehindTheRobot) {
  Scan scan;
  scan.first_angle = static_cast<float>(-M_PI);
  scan.angle_step = static_cast<float>(2 * M_PI / 360);
  scan.max_range = 20.0f;
  scan.ranges.assign(360, 4.0f);
  const std::vector<Point2> points = {{-4.0, 0.01}, {-4.0, -0.01}, {-2.0, 0.0}, {0.0, 6.0}};
  const std::vector<Sightings> seen = CountSightings(points, {scan});
  EXPECT_EQ(seen[0].returns, 1u);
  EXPECT_EQ(seen[1].returns, 1u);
  EXPECT_EQ(seen[2].through, 1u);
  EXPECT_EQ(seen[3].returns + seen[3].through, 0u);
}

TEST(SightingsTest, BeamsWithoutReturnClearUpToTheirLimit) {
  Scan scan = WallScan(0.0);
  for (float& r : scan.ranges) r = scan.max_range;  // nothing returned
  SightingOptions options;
  options.no_return_clear_m = 10.0;
  const std::vector<Sightings> seen = CountSightings({{8.0, 0.0}, {12.0, 0.0}}, {scan}, options);
  EXPECT_EQ(seen[0].through, 1u);
  EXPECT_EQ(seen[1].returns + seen[1].through, 0u);
}

// Over the work bound, every k-th scan is read: the counts shrink, the
// shares stay.
TEST(SightingsTest, ManyPointsAndScansReadEveryKthScan) {
  std::vector<Scan> scans;
  for (int k = 0; k < 6; ++k) scans.push_back(WallScan(0.1 * k));
  const std::vector<Point2> points = {{5.0, 0.2}, {2.0, 0.1}};
  SightingOptions options;
  options.max_point_scan_pairs = 12;  // 2 points x 6 scans: all read
  const std::vector<Sightings> all = CountSightings(points, scans, options);
  EXPECT_EQ(all[0].returns, 6u);
  EXPECT_EQ(all[1].through, 6u);
  options.max_point_scan_pairs = 5;  // every third scan
  const std::vector<Sightings> some = CountSightings(points, scans, options);
  EXPECT_EQ(some[0].returns, 2u);
  EXPECT_EQ(some[0].through, 0u);
  EXPECT_EQ(some[1].through, 2u);
  EXPECT_EQ(some[1].returns, 0u);
}

TEST(SightingsTest, NonFiniteInputCountsNeitherWay) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Scan bad_pose = WallScan(0.0);
  bad_pose.pose.theta = nan;
  Scan bad_ranges = WallScan(0.0);
  for (float& r : bad_ranges.ranges) r = std::numeric_limits<float>::quiet_NaN();
  Scan no_step = WallScan(0.0);
  no_step.angle_step = 0.0f;
  const std::vector<Sightings> seen =
      CountSightings({{5.0, 0.0}, {2.0, 0.0}, {nan, 1.0}}, {bad_pose, bad_ranges, no_step, Scan{}});
  for (const Sightings& s : seen) EXPECT_EQ(s.returns + s.through, 0u);
  const std::vector<Sightings> with_good = CountSightings({{nan, 1.0}, {5.0, 0.0}}, {WallScan(0.0)});
  EXPECT_EQ(with_good[0].returns + with_good[0].through, 0u);
  EXPECT_EQ(with_good[1].returns, 1u);
}

}  // namespace
}  // namespace lmd
