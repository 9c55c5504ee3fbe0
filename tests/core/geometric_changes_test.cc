#include "core/change/geometric_changes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "core/eval/retrieval_metrics.h"
#include "core/sim/change.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

TEST(GeometricChangesTest, AnUnchangedMapHasNoMasks) {
  for (size_t i = 0; i < DemoMaps().size(); i += 37) {
    const LocalMap& map = DemoMaps()[i];
    const PreparedMap prepared = PrepareMap(map);
    EXPECT_TRUE(GeometricChanges(map.points, map.trajectory, map.scans, {{&prepared, Pose2{}, 7}}).empty()) << map.id;
  }
}

// The simulated change of DESIGN.md §4 against the unchanged map, at the true
// pose: the top mask is the change in most tasks.
TEST(GeometricChangesTest, TheTopMaskIsTheSimulatedChange) {
  std::mt19937_64 rng(5);
  int tasks = 0, found = 0;
  for (size_t i = 0; i < DemoMaps().size() && tasks < 20; i += 13) {
    const LocalMap& map = DemoMaps()[i];
    LocalMap changed = map;
    Result<SimulatedChange> change = ApplySimulatedChange(changed, rng);
    if (!change.ok()) continue;
    ++tasks;
    const PreparedMap prepared = PrepareMap(map);
    const std::vector<ChangeMask> masks =
        GeometricChanges(changed.points, changed.trajectory, changed.scans, {{&prepared, Pose2{}, 7}});
    if (masks.empty()) continue;
    EXPECT_EQ(masks[0].db_map_id, 7u);
    EXPECT_EQ(masks[0].rank, 0u);
    for (size_t r = 1; r < masks.size(); ++r) EXPECT_GE(masks[r - 1].score, masks[r].score);
    found += MaskHitsChange(masks[0].points, change->changed_points, 0.5) ? 1 : 0;
  }
  ASSERT_EQ(tasks, 20);
  EXPECT_GE(found, 18) << "top mask on the change in " << found << " of " << tasks;
}

// The simulated objects as only the one scan that saw most of them saw them
// (the other scans as before the change: they looked through that spot) are
// something that moved while the robot mapped, not a change of the map.
TEST(GeometricChangesTest, AThingTheOtherScansSawThroughIsNoChange) {
  std::mt19937_64 rng(11);
  int tasks = 0, static_found = 0, moving_found = 0, moving_kept = 0;
  for (size_t i = 0; i < DemoMaps().size() && tasks < 12; i += 11) {
    const LocalMap& map = DemoMaps()[i];
    LocalMap changed = map;
    Result<SimulatedChange> change = ApplySimulatedChange(changed, rng);
    if (!change.ok()) continue;
    ++tasks;
    size_t seer = 0, most = 0;
    for (size_t s = 0; s < map.scans.size(); ++s) {
      size_t shorter = 0;
      for (size_t b = 0; b < map.scans[s].ranges.size(); ++b) {
        shorter += changed.scans[s].ranges[b] < map.scans[s].ranges[b] ? 1 : 0;
      }
      if (shorter > most) most = shorter, seer = s;
    }
    std::vector<Scan> moving_scans = map.scans;
    moving_scans[seer] = changed.scans[seer];
    const PreparedMap db = PrepareMap(map);
    auto found = [&](const std::vector<Scan>& scans, const GeometricChangeOptions& options) {
      for (const ChangeMask& m : GeometricChanges(changed.points, changed.trajectory, scans, {{&db, Pose2{}, 1}}, options)) {
        if (MaskHitsChange(m.points, change->changed_points, 0.5)) return 1;
      }
      return 0;
    };
    GeometricChangeOptions keep_all;
    keep_all.seen_through_share = 1.0;
    static_found += found(changed.scans, {});
    moving_found += found(moving_scans, {});
    moving_kept += found(moving_scans, keep_all);
  }
  ASSERT_EQ(tasks, 12);
  EXPECT_GE(static_found, 11);
  EXPECT_LE(moving_found, 2);
  EXPECT_GE(moving_kept, 11);
}

// Objects that another stored map of the place already shows are not new;
// a mask is credited to the map that saw its points free.
TEST(GeometricChangesTest, AnObjectAnotherStoredMapShowsIsNoChange) {
  std::mt19937_64 rng(9);
  const LocalMap& map = DemoMaps()[60];
  LocalMap changed = map;
  ASSERT_TRUE(ApplySimulatedChange(changed, rng).ok());
  const PreparedMap before = PrepareMap(map);
  const PreparedMap after = PrepareMap(changed);  // a stored map made after the change
  const std::vector<ChangeMask> against_before =
      GeometricChanges(changed.points, changed.trajectory, changed.scans, {{&before, Pose2{}, 1}});
  ASSERT_FALSE(against_before.empty());
  EXPECT_EQ(against_before[0].db_map_id, 1u);
  EXPECT_TRUE(
      GeometricChanges(changed.points, changed.trajectory, changed.scans, {{&before, Pose2{}, 1}, {&after, Pose2{}, 2}}).empty());
  // Listed first but without free space, the bare copy never gets the credit.
  LocalMap bare;
  bare.points = map.points;
  const PreparedMap bare_prepared = PrepareMap(bare);
  const std::vector<ChangeMask> credited =
      GeometricChanges(changed.points, changed.trajectory, changed.scans, {{&bare_prepared, Pose2{}, 3}, {&before, Pose2{}, 1}});
  ASSERT_EQ(credited.size(), against_before.size());
  for (const ChangeMask& mask : credited) EXPECT_EQ(mask.db_map_id, 1u);
}

// Cells of `db`'s free grid (centres, own frame) whose free margin (the
// default free_margin_m) is whole or not, at least 0.6 m from every db point,
// with a range from the trajectory in [lo, hi).
std::vector<Point2> FreeCells(const LocalMap& map, const PreparedMap& db, bool deep, double lo, double hi) {
  const OccupancyGrid& g = db.occupancy;
  const int reach = static_cast<int>(std::lround(GeometricChangeOptions().free_margin_m / g.cell_m()));
  std::vector<Point2> out;
  for (int y = reach; y + reach < g.height(); ++y) {
    for (int x = reach; x + reach < g.width(); ++x) {
      if (g.at(x, y) != CellState::kFree) continue;
      bool margin = true;
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) margin = margin && g.at(x + dx, y + dy) == CellState::kFree;
      }
      if (margin != deep) continue;
      const Point2 c = g.CellCentre(x, y);
      double dist2 = 0;
      if (NearestPoint(db, c, 0.6, &dist2) >= 0) continue;
      double range = 1e9;
      for (const Pose2& t : map.trajectory) range = std::min(range, std::hypot(t.x - c.x, t.y - c.y));
      if (range >= lo && range < hi) out.push_back(c);
    }
  }
  return out;
}

// Two new objects: a small one in open space next to the robot and a larger
// one far away (or at the edge of the space the stored map saw free). The
// near, well-observed one ranks first; by point count alone it would not.
TEST(GeometricChangesTest, WellObservedChangesOutrankLargerOnesFarAwayOrAtTheEdgeOfFreeSpace) {
  for (const bool edge : {false, true}) {
    SCOPED_TRACE(edge ? "edge of free space" : "far away");
    int tried = 0;
    for (size_t i = 0; i < DemoMaps().size() && tried < 3; i += 17) {
      const LocalMap& map = DemoMaps()[i];
      const PreparedMap db = PrepareMap(map);
      const std::vector<Point2> near = FreeCells(map, db, true, 0.5, 2.0);
      const std::vector<Point2> other = edge ? FreeCells(map, db, false, 0.5, 2.0) : FreeCells(map, db, true, 8.0, 1e9);
      // An object of `n` points around cell centre c (all in that cell).
      auto object = [](const Point2& c, int n, LocalMap* query) {
        for (int k = 0; k < n; ++k) query->points.push_back({c.x + 0.01 * (k % 3 - 1), c.y + 0.01 * (k / 3 - 1)});
      };
      const Point2* a = near.empty() ? nullptr : &near.front();
      const Point2* b = nullptr;
      for (const Point2& c : other) {
        if (a && std::hypot(c.x - a->x, c.y - a->y) > 2.0) { b = &c; break; }
      }
      if (!a || !b) continue;
      ++tried;
      LocalMap query = map;
      object(*a, 5, &query);
      object(*b, 8, &query);
      // The objects are points only: the map's scans pass through them, which
      // would mark them as moving things (seen_through_share), so no scans.
      const std::vector<ChangeMask> ranked = GeometricChanges(query.points, query.trajectory, {}, {{&db, Pose2{}, 1}});
      ASSERT_EQ(ranked.size(), 2u) << map.id;
      EXPECT_EQ(ranked[0].points.size(), 5u) << map.id;
      GeometricChangeOptions by_count;
      by_count.rank_by_evidence = false;
      const std::vector<ChangeMask> counted =
          GeometricChanges(query.points, query.trajectory, {}, {{&db, Pose2{}, 1}}, by_count);
      ASSERT_EQ(counted.size(), 2u) << map.id;
      EXPECT_EQ(counted[0].points.size(), 8u) << map.id;
    }
    EXPECT_EQ(tried, 3);
  }
}

// A small object next to the robot is reported where the stored map explains
// the rest of the query, and not where as much of the query again is
// unexplained elsewhere (scattered points in its free space, as a pose a
// little off leaves): there the floor of evidence is raised, and a fixed
// floor (floor_doubling_share 0) keeps the object either way.
TEST(GeometricChangesTest, TheEvidenceFloorRisesWithWhatIsUnexplainedElsewhere) {
  int tried = 0;
  for (size_t i = 0; i < DemoMaps().size() && tried < 3; i += 19) {
    const LocalMap& map = DemoMaps()[i];
    const PreparedMap db = PrepareMap(map);
    const std::vector<Point2> near = FreeCells(map, db, true, 0.5, 2.0);
    if (near.empty()) continue;
    const Point2 a = near.front();
    LocalMap clean = map;
    for (int k = 0; k < 4; ++k) clean.points.push_back({a.x + 0.02 * k, a.y});
    // Points alone in free space, more than merge_radius_m from each other
    // and from the object: change points that form no mask.
    LocalMap noisy = clean;
    size_t scattered = 0;
    for (const Point2& c : FreeCells(map, db, false, 0.5, 1e9)) {
      bool apart = std::hypot(c.x - a.x, c.y - a.y) > 2.0;
      for (size_t k = clean.points.size(); k < noisy.points.size() && apart; ++k) {
        apart = std::hypot(c.x - noisy.points[k].x, c.y - noisy.points[k].y) > 1.5;
      }
      if (apart) noisy.points.push_back(c), ++scattered;
    }
    if (scattered < 5) continue;
    ++tried;
    const std::vector<ChangeMask> unfloored = GeometricChanges(clean.points, clean.trajectory, {}, {{&db, Pose2{}, 1}});
    ASSERT_EQ(unfloored.size(), 1u) << map.id;
    GeometricChangeOptions fixed;
    fixed.min_evidence = 0.9 * unfloored[0].score;
    GeometricChangeOptions rising = fixed;
    // The scattered points double the floor.
    rising.floor_doubling_share = static_cast<double>(scattered) / noisy.points.size();
    EXPECT_EQ(GeometricChanges(clean.points, clean.trajectory, {}, {{&db, Pose2{}, 1}}, rising).size(), 1u) << map.id;
    EXPECT_TRUE(GeometricChanges(noisy.points, noisy.trajectory, {}, {{&db, Pose2{}, 1}}, rising).empty()) << map.id;
    EXPECT_EQ(GeometricChanges(noisy.points, noisy.trajectory, {}, {{&db, Pose2{}, 1}}, fixed).size(), 1u) << map.id;
  }
  EXPECT_EQ(tried, 3);
}

// Poses that are not finite give no range (as no trajectory), never NaN scores.
TEST(GeometricChangesTest, ANonFiniteTrajectoryRanksAsNoTrajectory) {
  std::mt19937_64 rng(3);
  const LocalMap& map = DemoMaps()[40];
  LocalMap changed = map;
  ASSERT_TRUE(ApplySimulatedChange(changed, rng).ok());
  const PreparedMap db = PrepareMap(map);
  const std::vector<ChangeMask> plain = GeometricChanges(changed.points, {}, changed.scans, {{&db, Pose2{}, 1}});
  ASSERT_FALSE(plain.empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<ChangeMask> odd =
      GeometricChanges(changed.points, {Pose2{nan, 0, 0}, Pose2{0, nan, 0}}, changed.scans, {{&db, Pose2{}, 1}});
  ASSERT_EQ(odd.size(), plain.size());
  for (size_t r = 0; r < odd.size(); ++r) {
    EXPECT_EQ(odd[r].score, plain[r].score) << r;
    EXPECT_EQ(odd[r].points.size(), plain[r].points.size()) << r;
  }
}

TEST(GeometricChangesTest, PointsTheDbMapNeverObservedAreNotChanges) {
  const LocalMap& map = DemoMaps()[20];
  const PreparedMap prepared = PrepareMap(map);
  // Far outside everything the db map's beams crossed.
  std::vector<Point2> far;
  for (int k = 0; k < 50; ++k) far.push_back({500.0 + 0.05 * k, 500.0});
  EXPECT_TRUE(GeometricChanges(far, {}, {}, {{&prepared, Pose2{}, 1}}).empty());
  // A db map without scans or trajectory has no free space: no masks.
  LocalMap bare;
  bare.points = map.points;
  LocalMap shifted = map;
  for (Point2& p : shifted.points) p.x += 1.0;
  const PreparedMap bare_prepared = PrepareMap(bare);
  EXPECT_TRUE(GeometricChanges(shifted.points, shifted.trajectory, shifted.scans, {{&bare_prepared, Pose2{}, 1}}).empty());
  EXPECT_TRUE(GeometricChanges(shifted.points, shifted.trajectory, shifted.scans, {}).empty());
}


}  // namespace
}  // namespace lmd
