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

// A map gridded for a coarse fit is read once more when it is matched
// against, and completed sharing the grid's pyramid; from then on neither
// call reads it. A map no longer stored gives null and leaves nothing held.
TEST(PreparedMapCacheTest, AGridIsCompletedOnceWhenAMatchNeedsTheWholeMap) {
  int reads = 0;
  const PreparedMapCache::ReadSource read = [&]() -> std::optional<PreparedMapCache::Source> {
    ++reads;
    LocalMap map;
    map.points = Wall();
    return PreparedMapCache::Source{map, 0.0};
  };
  PreparedMapCache cache(1 << 30);
  const PreparedMapOptions options;
  const auto grid = cache.SearchGrid("c", 1, options, read);
  ASSERT_NE(grid, nullptr);
  EXPECT_TRUE(grid->SearchGridOnly());
  EXPECT_EQ(reads, 1);
  const LikelihoodLevel* base = &grid->level(0);
  const auto complete = cache.Prepared("c", 1, options, read);
  ASSERT_NE(complete, nullptr);
  EXPECT_FALSE(complete->SearchGridOnly());
  EXPECT_EQ(&complete->level(0), base);
  EXPECT_EQ(reads, 2);
  EXPECT_EQ(cache.Prepared("c", 1, options, read), complete);
  EXPECT_EQ(cache.SearchGrid("c", 1, options, read), complete);
  EXPECT_EQ(reads, 2);
  EXPECT_EQ(cache.size(), 1u);

  const PreparedMapCache::ReadSource gone = [] { return std::optional<PreparedMapCache::Source>(); };
  EXPECT_EQ(cache.Prepared("c", 2, options, gone), nullptr);
  EXPECT_EQ(cache.SearchGrid("c", 2, options, gone), nullptr);
  EXPECT_EQ(cache.size(), 1u);
}

}  // namespace
}  // namespace lmd
