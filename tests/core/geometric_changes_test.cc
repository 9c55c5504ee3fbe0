#include "core/change/geometric_changes.h"

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
    EXPECT_TRUE(GeometricChanges(map.points, {{&prepared, Pose2{}, 7}}).empty()) << map.id;
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
    const std::vector<ChangeMask> masks = GeometricChanges(changed.points, {{&prepared, Pose2{}, 7}});
    if (masks.empty()) continue;
    EXPECT_EQ(masks[0].db_map_id, 7u);
    EXPECT_EQ(masks[0].rank, 0u);
    for (size_t r = 1; r < masks.size(); ++r) EXPECT_GE(masks[r - 1].score, masks[r].score);
    found += MaskHitsChange(masks[0].points, change->changed_points, 0.5) ? 1 : 0;
  }
  ASSERT_EQ(tasks, 20);
  EXPECT_GE(found, 18) << "top mask on the change in " << found << " of " << tasks;
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
  const std::vector<ChangeMask> against_before = GeometricChanges(changed.points, {{&before, Pose2{}, 1}});
  ASSERT_FALSE(against_before.empty());
  EXPECT_EQ(against_before[0].db_map_id, 1u);
  EXPECT_TRUE(GeometricChanges(changed.points, {{&before, Pose2{}, 1}, {&after, Pose2{}, 2}}).empty());
  // Listed first but without free space, the bare copy never gets the credit.
  LocalMap bare;
  bare.points = map.points;
  const PreparedMap bare_prepared = PrepareMap(bare);
  const std::vector<ChangeMask> credited =
      GeometricChanges(changed.points, {{&bare_prepared, Pose2{}, 3}, {&before, Pose2{}, 1}});
  ASSERT_EQ(credited.size(), against_before.size());
  for (const ChangeMask& mask : credited) EXPECT_EQ(mask.db_map_id, 1u);
}

TEST(GeometricChangesTest, PointsTheDbMapNeverObservedAreNotChanges) {
  const LocalMap& map = DemoMaps()[20];
  const PreparedMap prepared = PrepareMap(map);
  // Far outside everything the db map's beams crossed.
  std::vector<Point2> far;
  for (int k = 0; k < 50; ++k) far.push_back({500.0 + 0.05 * k, 500.0});
  EXPECT_TRUE(GeometricChanges(far, {{&prepared, Pose2{}, 1}}).empty());
  // A db map without scans or trajectory has no free space: no masks.
  LocalMap bare;
  bare.points = map.points;
  LocalMap shifted = map;
  for (Point2& p : shifted.points) p.x += 1.0;
  const PreparedMap bare_prepared = PrepareMap(bare);
  EXPECT_TRUE(GeometricChanges(shifted.points, {{&bare_prepared, Pose2{}, 1}}).empty());
  EXPECT_TRUE(GeometricChanges(shifted.points, {}).empty());
}

}  // namespace
}  // namespace lmd
