// The anchored maps a prior query looks at: nearest the query's path first,
// the newest first where many are equally near, and never more than a cell
// can answer however many maps a fleet piled up at one place.
#include "core/localize/anchor_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lmd {
namespace {

// A map whose robot drove from (x, y) 4 m along +x, anchored there, its
// points within 3 m of the path; `derived`: anchored by lmdd from a fix.
void Drove(AnchorIndex* index, uint64_t id, double x, double y, bool derived = false) {
  std::vector<Pose2> trajectory;
  for (double s = 0; s <= 4.0; s += 0.25) trajectory.push_back({s, 0.0, 0.0});
  index->Set(id, {x, y, 0.0}, {-3.0, -3.0}, {7.0, 3.0}, trajectory, derived);
}

std::vector<uint64_t> Ids(const std::vector<MapSource::Anchored>& maps) {
  std::vector<uint64_t> ids;
  for (const MapSource::Anchored& a : maps) ids.push_back(a.map_id);
  return ids;
}

const std::vector<Point2> kQueryPath = {{0.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}, {3.0, 0.0}};

TEST(AnchorIndexTest, NearestByPathRanksByTheGapBetweenTrajectories) {
  AnchorIndex index;
  Drove(&index, 1, 0.0, 6.0);   // 6 m beside the query's path
  Drove(&index, 2, 0.0, 0.5);   // half a metre beside it
  Drove(&index, 3, 0.0, -2.0);  // 2 m
  Drove(&index, 4, 30.0, 0.0);  // 27 m ahead
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 10.0, 10)), (std::vector<uint64_t>{2, 3, 1}));
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 10.0, 2)), (std::vector<uint64_t>{2, 3}));
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 40.0, 10)), (std::vector<uint64_t>{2, 3, 1, 4}));
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 10.0, 10, [](uint64_t id) { return id == 2; })),
            (std::vector<uint64_t>{3, 1}));
  EXPECT_TRUE(index.NearestByPath({}, 10.0, 10).empty());
  EXPECT_TRUE(index.NearestByPath(kQueryPath, std::nan(""), 10).empty());
}

// Within a metre the survey's maps (given anchors) come before those lmdd
// anchored from fixes, however many newer ones the fleet stored.
TEST(AnchorIndexTest, GivenAnchorsComeBeforeDerivedOnesEquallyNear) {
  AnchorIndex index;
  Drove(&index, 1, 0.0, 0.3);          // given, 0.3 m beside the query's path
  Drove(&index, 2, 0.0, 1.6);          // given, 1.6 m
  for (uint64_t id = 10; id < 500; ++id) Drove(&index, id, 0.0, 0.1, true);  // derived, 0.1 m
  Drove(&index, 600, 0.0, 5.0, true);  // derived, 5 m
  const std::vector<uint64_t> ids = Ids(index.NearestByPath(kQueryPath, 10.0, 4));
  EXPECT_EQ(ids, (std::vector<uint64_t>{1, 499, 498, 497}));
  const std::vector<uint64_t> more = Ids(index.NearestByPath(kQueryPath, 10.0, 600));
  ASSERT_EQ(more.size(), 493u);  // all of them: 1, the 490 derived at 0.1 m, 2, 600
  EXPECT_EQ(more[1], 499u);
  EXPECT_EQ(more[490], 10u);
  EXPECT_EQ(more[491], 2u);
  EXPECT_EQ(more[492], 600u);
  const std::vector<uint64_t> near = Ids(index.Near({1.0, 0.0}, 2.0, 3));
  EXPECT_TRUE(std::find(near.begin(), near.end(), 1) != near.end());
  EXPECT_TRUE(std::find(near.begin(), near.end(), 2) != near.end());
  EXPECT_TRUE(std::find(near.begin(), near.end(), 499) != near.end());
  EXPECT_TRUE(std::find(near.begin(), near.end(), 10) == near.end());
}

TEST(AnchorIndexTest, AMapWithoutTrajectoryStandsAtItsOrigin) {
  AnchorIndex index;
  index.Set(7, {1.0, 1.0, 0.5}, {-2.0, -2.0}, {2.0, 2.0});
  Drove(&index, 8, 0.0, 4.0);
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 10.0, 10)), (std::vector<uint64_t>{7, 8}));
}

TEST(AnchorIndexTest, ReanchoringAndRemovingMoveAMapOutOfItsOldPlace) {
  AnchorIndex index;
  Drove(&index, 1, 0.0, 0.0);
  Drove(&index, 2, 0.0, 1.0);
  Drove(&index, 1, 50.0, 50.0);  // re-anchored far away
  EXPECT_EQ(Ids(index.NearestByPath(kQueryPath, 5.0, 10)), (std::vector<uint64_t>{2}));
  EXPECT_EQ(Ids(index.Near({1.0, 0.0}, 3.0, 100)), (std::vector<uint64_t>{2}));
  EXPECT_TRUE(index.Remove(2));
  EXPECT_FALSE(index.Remove(2));
  EXPECT_TRUE(index.NearestByPath(kQueryPath, 5.0, 10).empty());
  EXPECT_TRUE(index.Near({1.0, 0.0}, 3.0, 100).empty());
  EXPECT_EQ(Ids(index.Near({52.0, 50.0}, 3.0, 100)), (std::vector<uint64_t>{1}));
}

// 3,000 robots' maps of one stretch of corridor: a query gets the newest,
// and no more of them than it asked for from each cell.
TEST(AnchorIndexTest, APlaceWithThousandsOfMapsAnswersWithItsNewest) {
  AnchorIndex index;
  const uint64_t kMaps = 3000;
  for (uint64_t id = 1; id <= kMaps; ++id) Drove(&index, id, 0.0, 0.0);
  const std::vector<uint64_t> nearest = Ids(index.NearestByPath(kQueryPath, 10.0, 8));
  std::vector<uint64_t> newest;
  for (uint64_t id = kMaps; id > kMaps - 8; --id) newest.push_back(id);
  EXPECT_EQ(nearest, newest);
  // Excluded maps take no place among those read.
  const std::vector<uint64_t> without = Ids(index.NearestByPath(kQueryPath, 10.0, 8, [&](uint64_t id) { return id > kMaps - 4; }));
  ASSERT_EQ(without.size(), 8u);
  EXPECT_EQ(without.front(), kMaps - 4);
  // The disk meets 4 cells of 10 m here; each gives at most its newest 50.
  const std::vector<uint64_t> near = Ids(index.Near({0.0, 0.0}, 4.0, 50));
  EXPECT_LE(near.size(), 4u * 50u);
  EXPECT_GE(near.size(), 50u);
  EXPECT_GT(*std::min_element(near.begin(), near.end()), kMaps - 4 * 50);
}

}  // namespace
}  // namespace lmd
