// Planned viewpoints on Helper A's simulator: two local maps of the same
// place, built from different passes of the route, get nearby viewpoints.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "core/describe/describer.h"
#include "core/eval/ground_truth.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd {
namespace {

// PlanViewpoint plans CoG without rooms and without free space (walls read
// occupied cells only): the frames must be those of the full plan, exactly.
TEST(ViewpointSimTest, CogWithoutFreeSpaceIsTheFullPlansCog) {
  SimulationOptions options = DefaultDemoOptions();
  options.route.length_m = 60.0;
  const std::vector<LocalMap> maps = SimulateLocalMaps(options);
  ASSERT_GE(maps.size(), 20u);
  ViewpointOptions cog;
  cog.planner = Planner::kCoG;
  for (const LocalMap& map : maps) {
    ASSERT_FALSE(map.scans.empty());
    const Frame full = PlanViewpointDetailed(map, cog).cog;
    const Frame plain = PlanViewpoint(map, cog);
    EXPECT_EQ(plain.origin.x, full.origin.x) << map.id;
    EXPECT_EQ(plain.origin.y, full.origin.y) << map.id;
    EXPECT_EQ(plain.heading, full.heading) << map.id;
  }
}

TEST(ViewpointSimTest, RevisitsOfAPlaceGetNearbyViewpoints) {
  SimulationOptions options = DefaultDemoOptions();
  options.route.length_m = 150.0;
  const std::vector<LocalMap> maps = SimulateLocalMaps(options);
  const std::vector<RelevantPair> pairs = FindRelevantPairs(maps);
  ASSERT_GE(pairs.size(), 20u);
  std::vector<Point2> origin(maps.size());
  std::vector<char> done(maps.size(), 0);
  std::vector<double> d;
  for (const RelevantPair& p : pairs) {
    for (size_t i : {p.query, p.relevant}) {
      if (done[i]) continue;
      origin[i] = TransformPoint(maps[i].truth.global_frame, PlanViewpoint(maps[i]).origin);
      done[i] = 1;
    }
    d.push_back(std::hypot(origin[p.query].x - origin[p.relevant].x, origin[p.query].y - origin[p.relevant].y));
  }
  std::sort(d.begin(), d.end());
  const double within_1m = static_cast<double>(std::lower_bound(d.begin(), d.end(), 1.0) - d.begin()) / d.size();
  std::printf("simulated: %zu pairs, median viewpoint distance %.2f m, %.0f%% within 1 m\n", d.size(), d[d.size() / 2],
              100 * within_1m);
  EXPECT_GE(within_1m, 0.45);  // measured 54 % (112 pairs, median 0.83 m, CoG) on this seed
}

}  // namespace
}  // namespace lmd
