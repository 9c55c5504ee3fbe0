#include "core/localize/prepared_map_cache.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

namespace lmd {
namespace {

std::vector<Point2> Wall() {
  std::vector<Point2> points;
  for (int i = 0; i < 50; ++i) points.push_back({0.1 * i, 0.0});
  return points;
}

// A map gridded for a coarse fit alone (RankByFit) and then matched against
// is held once: completed, the complete map replaces its grid, and a grid
// never replaces a complete map (two queries racing on one map).
TEST(PreparedMapCacheTest, ACompletedSearchGridReplacesItsGridAndNeverTheReverse) {
  const auto grid = std::make_shared<const PreparedMap>(PrepareSearchGrid(Wall()));
  const auto complete = std::make_shared<const PreparedMap>(PreparePoints(Wall()));
  ASSERT_TRUE(grid->SearchGridOnly());
  ASSERT_FALSE(complete->SearchGridOnly());

  PreparedMapCache cache(1 << 30);
  cache.Put("c", 1, grid);
  EXPECT_EQ(cache.Find("c", 1), grid);
  EXPECT_EQ(cache.bytes(), grid->MemoryBytes());
  cache.Put("c", 1, complete);
  EXPECT_EQ(cache.Find("c", 1), complete);
  EXPECT_EQ(cache.bytes(), complete->MemoryBytes());
  cache.Put("c", 1, std::make_shared<const PreparedMap>(PrepareSearchGrid(Wall())));
  EXPECT_EQ(cache.Find("c", 1), complete);
  EXPECT_EQ(cache.bytes(), complete->MemoryBytes());
  cache.Put("c", 1, std::make_shared<const PreparedMap>(PreparePoints(Wall())));
  EXPECT_EQ(cache.Find("c", 1), complete);  // a complete map is kept as it is
}

// The least recently used map goes first once the budget is spent, and is
// counted.
TEST(PreparedMapCacheTest, DropsTheLeastRecentBeyondItsBudget) {
  const auto map = [] { return std::make_shared<const PreparedMap>(PreparePoints(Wall())); };
  const size_t each = map()->MemoryBytes();
  PreparedMapCache cache(2 * each + each / 2);
  cache.Put("c", 1, map());
  cache.Put("c", 2, map());
  ASSERT_NE(cache.Find("c", 1), nullptr);  // 1 is now the most recent
  cache.Put("c", 3, map());
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_EQ(cache.evictions(), 1u);
  EXPECT_EQ(cache.bytes(), 2 * each);
  EXPECT_NE(cache.Find("c", 1), nullptr);
  EXPECT_EQ(cache.Find("c", 2), nullptr);
  EXPECT_NE(cache.Find("c", 3), nullptr);
  EXPECT_EQ(cache.Find("other", 1), nullptr);  // keyed by collection too
}

}  // namespace
}  // namespace lmd
