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
    EXPECT_TRUE(GeometricChanges(map.points, PrepareMap(map), Pose2{}, 7).empty()) << map.id;
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
    const std::vector<ChangeMask> masks = GeometricChanges(changed.points, PrepareMap(map), Pose2{}, 7);
    if (masks.empty()) continue;
    EXPECT_EQ(masks[0].db_map_id, 7u);
    EXPECT_EQ(masks[0].rank, 0u);
    for (size_t r = 1; r < masks.size(); ++r) EXPECT_GE(masks[r - 1].score, masks[r].score);
    found += MaskHitsChange(masks[0].points, change->changed_points, 0.5) ? 1 : 0;
  }
  ASSERT_EQ(tasks, 20);
  EXPECT_GE(found, 18) << "top mask on the change in " << found << " of " << tasks;
}

TEST(GeometricChangesTest, PointsTheDbMapNeverObservedAreNotChanges) {
  const LocalMap& map = DemoMaps()[20];
  const PreparedMap prepared = PrepareMap(map);
  // Far outside everything the db map's beams crossed.
  std::vector<Point2> far;
  for (int k = 0; k < 50; ++k) far.push_back({500.0 + 0.05 * k, 500.0});
  EXPECT_TRUE(GeometricChanges(far, prepared, Pose2{}, 1).empty());
  // A db map without scans or trajectory has no free space: no masks.
  LocalMap bare;
  bare.points = map.points;
  LocalMap shifted = map;
  for (Point2& p : shifted.points) p.x += 1.0;
  EXPECT_TRUE(GeometricChanges(shifted.points, PrepareMap(bare), Pose2{}, 1).empty());
}

}  // namespace
}  // namespace lmd
