// The change simulator (DESIGN.md §4): objects in a 1-2 m region the laser sees.
#include "core/sim/change.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

bool Inside(const SimulatedChange& c, const Point2& p) {
  const Point2& lo = c.region_corners[0];
  const Point2& hi = c.region_corners[2];
  return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y;
}

std::set<std::pair<double, double>> PointSet(const std::vector<Point2>& pts) {
  std::set<std::pair<double, double>> s;
  for (const Point2& p : pts) s.insert({p.x, p.y});
  return s;
}

TEST(ChangeSimulator, ChangesPointsInsideTheRegionAndNowhereElse) {
  for (size_t index : {10u, 57u, 150u}) {
    LocalMap map = DemoMaps().at(index);
    const LocalMap before = map;
    std::mt19937_64 rng(index);
    auto change = ApplySimulatedChange(map, rng);
    ASSERT_TRUE(change.ok()) << change.status().ToString();
    ASSERT_EQ(change->region_corners.size(), 4u);
    const double w = change->region_corners[2].x - change->region_corners[0].x;
    const double h = change->region_corners[2].y - change->region_corners[0].y;
    EXPECT_GE(w, 1.0);
    EXPECT_LE(w, 2.0);
    EXPECT_GE(h, 1.0);
    EXPECT_LE(h, 2.0);
    ASSERT_FALSE(change->changed_points.empty());
    for (const Point2& p : change->changed_points) EXPECT_TRUE(Inside(*change, p));
    // Outside the region: exactly the old points.
    std::vector<Point2> old_out, new_out;
    for (const Point2& p : before.points)
      if (!Inside(*change, p)) old_out.push_back(p);
    for (const Point2& p : map.points)
      if (!Inside(*change, p)) new_out.push_back(p);
    EXPECT_EQ(PointSet(old_out), PointSet(new_out));
    // The changed points are new points of the map.
    const auto now = PointSet(map.points), then = PointSet(before.points);
    for (const Point2& p : change->changed_points) {
      EXPECT_TRUE(now.count({p.x, p.y}));
      EXPECT_FALSE(then.count({p.x, p.y}));
    }
    // Beams only got shorter (objects occlude), and some did.
    size_t shorter = 0;
    for (size_t s = 0; s < map.scans.size(); ++s) {
      for (size_t i = 0; i < map.scans[s].ranges.size(); ++i) {
        EXPECT_LE(map.scans[s].ranges[i], before.scans[s].ranges[i]);
        shorter += map.scans[s].ranges[i] < before.scans[s].ranges[i] ? 1 : 0;
      }
    }
    EXPECT_GT(shorter, 0u);
  }
}

TEST(ChangeSimulator, RegionIsAwayFromTheRobot) {
  LocalMap map = DemoMaps().at(33);
  std::mt19937_64 rng(4);
  auto change = ApplySimulatedChange(map, rng);
  ASSERT_TRUE(change.ok());
  for (const Pose2& p : map.trajectory) EXPECT_FALSE(Inside(*change, {p.x, p.y}));
}

TEST(ChangeSimulator, SameRandomStateSameChange) {
  LocalMap a = DemoMaps().at(80), b = DemoMaps().at(80), c = DemoMaps().at(80);
  std::mt19937_64 ra(42), rb(42), rc(43);
  auto ca = ApplySimulatedChange(a, ra);
  auto cb = ApplySimulatedChange(b, rb);
  auto cc = ApplySimulatedChange(c, rc);
  ASSERT_TRUE(ca.ok() && cb.ok() && cc.ok());
  EXPECT_EQ(ca->region_corners[0].x, cb->region_corners[0].x);
  EXPECT_EQ(ca->changed_points.size(), cb->changed_points.size());
  EXPECT_EQ(a.points.size(), b.points.size());
  EXPECT_NE(ca->region_corners[0].x, cc->region_corners[0].x);
}

// A map with one scan of one beam: many regions placed along it get objects
// that miss the beam, so the simulator must draw again.
LocalMap OneBeamMap() {
  LocalMap m;
  m.id = "one-beam";
  Scan s;
  s.first_angle = 0;
  s.angle_step = 0.01f;
  s.max_range = 30;
  s.ranges = {6.0f};
  m.scans.push_back(s);
  m.trajectory.push_back({});
  m.points = PointsFromScans(m.scans);
  return m;
}

TEST(ChangeSimulator, DrawsAgainUntilABeamHitsAnObject) {
  int single_draw_failures = 0;
  for (uint64_t seed = 0; seed < 40; ++seed) {
    LocalMap m = OneBeamMap();
    std::mt19937_64 rng(seed);
    auto change = ApplySimulatedChange(m, rng);
    ASSERT_TRUE(change.ok()) << "seed " << seed << ": " << change.status().ToString();
    EXPECT_LT(m.scans[0].ranges[0], 6.0f);
    ASSERT_EQ(change->changed_points.size(), 1u);
    LocalMap once = OneBeamMap();
    std::mt19937_64 rng1(seed);
    ChangeOptions one;
    one.max_attempts = 1;
    auto r = ApplySimulatedChange(once, rng1, one);
    if (!r.ok()) {
      EXPECT_EQ(r.status().code(), Status::Code::kNotFound);
      EXPECT_EQ(once.scans[0].ranges[0], 6.0f) << "a failed draw leaves the map alone";
      ++single_draw_failures;
    }
  }
  EXPECT_GT(single_draw_failures, 0) << "the one-beam map should make some first draws miss";
}

TEST(ChangeSimulator, MapWithoutScansIsInvalidArgument) {
  LocalMap m;
  m.points = {{1, 1}};
  std::mt19937_64 rng(1);
  auto r = ApplySimulatedChange(m, rng);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), Status::Code::kInvalidArgument);
}

TEST(ChangeSimulator, WorksOnMapsFromARealLog) {
  const std::string path = std::string(LMD_SHARED_DATA_DIR) + "/fr101.log.gz";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "real log not found: " << path;
  auto log = ReadCarmenLog(path);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  std::vector<LocalMap> maps = BuildLocalMaps(*log);
  ASSERT_GT(maps.size(), 50u);
  std::mt19937_64 rng(7);
  for (size_t i = 0; i < maps.size(); i += 25) {
    const size_t before = maps[i].points.size();
    auto change = ApplySimulatedChange(maps[i], rng);
    ASSERT_TRUE(change.ok()) << change.status().ToString();
    EXPECT_FALSE(change->changed_points.empty());
    EXPECT_GT(maps[i].points.size() + 50, before);
  }
}

}  // namespace
}  // namespace lmd
