#include "server/indexing.h"

#include <gtest/gtest.h>

#include "core/describe/lmd_codec.h"
#include "core/sim/simulate.h"

namespace lmd::server {
namespace {

// The paper's descriptor an insert stores reuses the compass of the map's
// preparation for the default method; it must be the descriptor the map
// has on its own.
TEST(IndexingTest, TheStoredDescriptorIsTheOneTheMapHasOnItsOwn) {
  const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  const IndexingConfig config = ProductIndexing(false);
  size_t compared = 0;
  for (size_t i = 0; i < maps.size(); i += 37) {
    const DescribedMap described = DescribeMap(maps[i], config, /*with_lmd=*/true);
    ASSERT_TRUE(described.lmd.has_value()) << i;
    const Lmd alone = DescribeForIndex(MethodView(maps[i]), config);
    EXPECT_EQ(EncodeLmd(*described.lmd), EncodeLmd(alone)) << i;
    EXPECT_DOUBLE_EQ(described.lmd->frame.heading, alone.frame.heading) << i;
    ++compared;
  }
  EXPECT_GE(compared, 5u);
}

// Where the paper's planner has a compass of its own, it uses it.
TEST(IndexingTest, APlannerWithItsOwnCompassDoesNotReuseThePreparations) {
  const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  IndexingConfig config = ProductIndexing(false);
  config.viewpoint.orientation.fine_step_deg = 0.7;
  size_t differ = 0, compared = 0;
  for (size_t i = 0; i < maps.size(); i += 37) {
    const DescribedMap described = DescribeMap(maps[i], config, /*with_lmd=*/true);
    ASSERT_TRUE(described.lmd.has_value()) << i;
    const Lmd alone = DescribeForIndex(MethodView(maps[i]), config);
    EXPECT_DOUBLE_EQ(described.lmd->frame.heading, alone.frame.heading) << i;
    differ += described.lmd->frame.heading != described.place.map->heading;
    ++compared;
  }
  EXPECT_GE(differ, compared / 2) << "the two compasses should differ at these steps";
}

}  // namespace
}  // namespace lmd::server
