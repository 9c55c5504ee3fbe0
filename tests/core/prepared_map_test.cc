#include "core/align/prepared_map.h"

#include <gtest/gtest.h>

#include <random>
#include <thread>

namespace lmd {
namespace {

// NearestPoint against brute force: a point exactly as near as the nearest
// (or none when none is within reach), for query points inside, around and
// outside the map, on points snapped to a grid (many exact ties) and not.
TEST(PreparedMapTest, NearestPointIsTheBruteForceNearest) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-3.0, 3.0), around(-4.0, 4.0);
  for (bool snapped : {false, true}) {
    std::vector<Point2> points;
    for (int i = 0; i < 400; ++i) {
      Point2 p{coord(rng), coord(rng)};
      if (snapped) p = {std::round(p.x * 10) / 10, std::round(p.y * 10) / 10};
      points.push_back(p);
    }
    const PreparedMap map = PreparePoints(points, PreparedMapOptions());
    for (int q = 0; q < 3000; ++q) {
      Point2 p{around(rng), around(rng)};
      if (snapped && q % 2 == 0) p = {std::round(p.x * 20) / 20, std::round(p.y * 20) / 20};
      for (double max_dist : {0.15, 0.3, 0.4}) {
        auto dist2 = [&](size_t j) {
          const double dx = map.points[j].x - p.x, dy = map.points[j].y - p.y;
          return dx * dx + dy * dy;
        };
        double want = max_dist * max_dist;
        bool any = false;
        for (size_t j = 0; j < map.points.size(); ++j) {
          if (dist2(j) <= want) want = dist2(j), any = true;
        }
        double got = -1.0;
        const int index = NearestPoint(map, p, max_dist, &got);
        ASSERT_EQ(index >= 0, any) << p.x << " " << p.y << " " << max_dist;
        if (!any) continue;
        EXPECT_EQ(got, want);
        EXPECT_EQ(dist2(static_cast<size_t>(index)), want);
      }
    }
  }
}

// The pyramid is built on first use, a level with those below it: a cache
// sizes a map before that, so MemoryBytes must count it already; copies and
// threads share one pyramid, and a level stays where it was built when
// coarser ones follow.
TEST(PreparedMapTest, LazyPyramidIsCountedBeforeItIsBuiltAndBuiltOnce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-6.0, 6.0);
  std::vector<Point2> points;
  for (int i = 0; i < 300; ++i) points.push_back({coord(rng), coord(rng)});
  const PreparedMap map = PreparePoints(points, PreparedMapOptions());
  const int levels = map.options.levels;
  ASSERT_EQ(levels, PreparedMapOptions().levels);
  const size_t before = map.MemoryBytes();
  const PreparedMap copy = map;
  const LikelihoodLevel* base = &copy.level(0);
  const std::vector<uint8_t> base_values = base->values;
  std::vector<const LikelihoodLevel*> seen(4, nullptr);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < seen.size(); ++t) {
    threads.emplace_back([&, t] { seen[t] = &(t % 2 ? copy : map).level(levels - 1); });
  }
  for (std::thread& t : threads) t.join();
  for (const LikelihoodLevel* top : seen) EXPECT_EQ(top, seen[0]);
  EXPECT_EQ(&map.level(0), base);
  EXPECT_EQ(base->values, base_values);
  EXPECT_TRUE(map.level(levels).values.empty());
  size_t pyramid = 0;
  for (int h = 0; h < levels; ++h) pyramid += map.level(h).values.size();
  EXPECT_GT(pyramid, 0u);
  EXPECT_EQ(map.MemoryBytes(), before);
  const PreparedMap no_pyramid = PreparePoints(points, [] {
    PreparedMapOptions o;
    o.levels = 1;
    return o;
  }());
  EXPECT_EQ(before - no_pyramid.MemoryBytes(), pyramid - no_pyramid.level(0).values.size());
}

}  // namespace
}  // namespace lmd
