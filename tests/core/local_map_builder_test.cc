// Local map windowing: one map per length_m of travel, a new one every step_m.
#include "core/localmap/local_map_builder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// A straight run along x at heading 0.3 rad... positions every `spacing` m,
// each scan a 3-beam fan returning 2 m.
LaserLog StraightLog(double length, double spacing, double heading = 0.3) {
  LaserLog log;
  for (double d = 0; d <= length + 1e-9; d += spacing) {
    Scan s;
    s.pose = {10 + d * std::cos(heading), -4 + d * std::sin(heading), heading};
    s.first_angle = -0.5f;
    s.angle_step = 0.5f;
    s.max_range = 30.0f;
    s.ranges = {2.0f, 2.0f, 30.0f};  // the last beam: no return
    log.scans.push_back(s);
  }
  return log;
}

TEST(LocalMapBuilder, OneMapPerStepOverTheRun) {
  const auto maps = BuildLocalMaps(StraightLog(20.0, 0.25));
  // Starts at 0, 1, ..., 15 m: 16 windows of 5 m fit in 20 m.
  ASSERT_EQ(maps.size(), 16u);
  for (size_t k = 0; k < maps.size(); ++k) {
    EXPECT_NEAR(maps[k].truth.travel_start, static_cast<double>(k), 1e-9);
    EXPECT_NEAR(maps[k].truth.travel_end - maps[k].truth.travel_start, 5.0, 1e-9);
    EXPECT_EQ(maps[k].trajectory.size(), 21u);  // 5 m / 0.25 m + 1
    EXPECT_EQ(maps[k].scans.size(), 21u);
    EXPECT_EQ(maps[k].id, std::to_string(k));
  }
}

TEST(LocalMapBuilder, LengthAndStepAreOptions) {
  LocalMapOptions o;
  o.length_m = 10.0;
  o.step_m = 2.5;
  o.id_prefix = "run";
  const auto maps = BuildLocalMaps(StraightLog(20.0, 0.25), o);
  ASSERT_EQ(maps.size(), 5u);  // starts 0, 2.5, 5, 7.5, 10
  EXPECT_NEAR(maps[4].truth.travel_start, 10.0, 1e-9);
  EXPECT_EQ(maps[4].id, "run-4");
  EXPECT_TRUE(BuildLocalMaps(StraightLog(4.0, 0.25)).empty()) << "shorter than one window";
}

TEST(LocalMapBuilder, MapsAreInTheirOwnFrameStartingAtTheOrigin) {
  const LaserLog log = StraightLog(10.0, 0.5);
  const auto maps = BuildLocalMaps(log);
  ASSERT_FALSE(maps.empty());
  const LocalMap& m = maps[2];
  EXPECT_DOUBLE_EQ(m.trajectory[0].x, 0.0);
  EXPECT_DOUBLE_EQ(m.trajectory[0].y, 0.0);
  EXPECT_DOUBLE_EQ(m.trajectory[0].theta, 0.0);
  // Straight ahead along the map's own x axis.
  EXPECT_NEAR(m.trajectory.back().x, 5.0, 1e-9);
  EXPECT_NEAR(m.trajectory.back().y, 0.0, 1e-9);
  // truth.global_frame = the first pose of the window in the log frame.
  const Pose2& g = m.truth.global_frame;
  EXPECT_NEAR(g.x, log.scans[4].pose.x, 1e-12);
  EXPECT_NEAR(g.theta, 0.3, 1e-12);
  // Points go back to where the scans saw them.
  const Point2 p = TransformPoint(g, m.points[0]);
  const double a = 0.3 - 0.5;
  EXPECT_NEAR(p.x, log.scans[4].pose.x + 2 * std::cos(a), 1e-5);
  EXPECT_NEAR(p.y, log.scans[4].pose.y + 2 * std::sin(a), 1e-5);
}

TEST(LocalMapBuilder, PointsAreDeduplicatedOnTheGridAndNoReturnGivesNone) {
  // All scans at one place (turning in place does not count as travel, so
  // use a log that creeps forward 1 mm per scan).
  LaserLog log = StraightLog(6.0, 0.001, 0.0);
  const auto maps = BuildLocalMaps(log);
  ASSERT_FALSE(maps.empty());
  std::set<std::pair<long, long>> cells;
  for (const Point2& p : maps[0].points) {
    EXPECT_TRUE(cells.insert({std::lround(std::floor(p.x / 0.1)), std::lround(std::floor(p.y / 0.1))}).second)
        << "two points in one 0.1 m cell";
  }
  // Two beams with a return per scan, 5 m of travel: each beam's endpoints
  // sweep 5 m -> about 50 cells each; the no-return beam adds nothing.
  EXPECT_GE(maps[0].points.size(), 95u);
  EXPECT_LE(maps[0].points.size(), 106u);
}

TEST(LocalMapBuilder, DeduplicatePointsKeepsTheFirstPointOfEachCellInOrder) {
  const std::vector<Point2> points = {{0.01, 0.01}, {0.05, 0.02}, {0.15, 0.0}, {0.01, 0.01}, {-0.05, 0.0}, {0.12, 0.09}};
  const std::vector<Point2> kept = DeduplicatePoints(points, 0.1);
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0].x, 0.01);
  EXPECT_EQ(kept[1].x, 0.15);
  EXPECT_EQ(kept[2].x, -0.05);
  // The points of a map BuildLocalMaps made all stay.
  const auto maps = BuildLocalMaps(StraightLog(6.0, 0.001, 0.0));
  ASSERT_FALSE(maps.empty());
  EXPECT_EQ(DeduplicatePoints(maps[0].points).size(), maps[0].points.size());
}

TEST(LocalMapBuilder, GapsInTheLogDoNotDuplicateMaps) {
  LaserLog log = StraightLog(10.0, 0.5);
  LaserLog jump = StraightLog(10.0, 0.5);
  for (Scan& s : jump.scans) s.pose.x += 100.0;  // a 100 m jump between the halves
  log.scans.insert(log.scans.end(), jump.scans.begin(), jump.scans.end());
  const auto maps = BuildLocalMaps(log);
  std::set<double> starts;
  for (const LocalMap& m : maps) EXPECT_TRUE(starts.insert(m.truth.travel_start).second);
  // As many maps as stepping start by start gives (counted before the
  // windowing learnt to skip ahead), one of them starting at the first scan
  // after the jump.
  EXPECT_EQ(maps.size(), 17u);
  bool starts_after_jump = false;
  for (const LocalMap& m : maps) starts_after_jump |= m.truth.global_frame.x == jump.scans[0].pose.x;
  EXPECT_TRUE(starts_after_jump);
}

// A jump of 1e12 m (a corrupt log the reader did not catch) costs one step
// of the windowing, not one per metre: without that this never returned.
TEST(LocalMapBuilder, AHugeJumpIsCrossedInOneStep) {
  LaserLog log = StraightLog(10.0, 0.5);
  LaserLog far = StraightLog(10.0, 0.5);
  for (Scan& s : far.scans) s.pose.x += 1e12;
  log.scans.insert(log.scans.end(), far.scans.begin(), far.scans.end());
  const auto maps = BuildLocalMaps(log);
  ASSERT_FALSE(maps.empty());
  EXPECT_EQ(maps.front().truth.travel_start, 0.0);
  EXPECT_GT(maps.back().truth.travel_start, 1e12);  // windows on both sides of the jump
  bool starts_after_jump = false;  // the first scan after the jump starts a map
  for (const LocalMap& m : maps) starts_after_jump |= m.truth.global_frame.x == far.scans[0].pose.x;
  EXPECT_TRUE(starts_after_jump);
}

TEST(LocalMapBuilder, KeepScansFalseDropsScansButKeepsPoints) {
  LocalMapOptions o;
  o.keep_scans = false;
  const auto maps = BuildLocalMaps(StraightLog(10.0, 0.5), o);
  ASSERT_FALSE(maps.empty());
  EXPECT_TRUE(maps[0].scans.empty());
  EXPECT_FALSE(maps[0].points.empty());
  EXPECT_EQ(maps[0].trajectory.size(), 11u);
}

}  // namespace
}  // namespace lmd
