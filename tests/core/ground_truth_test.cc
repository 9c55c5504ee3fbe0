// Ground truth of the evaluation protocol: relevant pairs and place overlap.
#include "core/eval/ground_truth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/io/carmen_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"

namespace lmd {
namespace {

// A map whose global points are `global` shifted by (dx, 0), stored in an
// own frame given by `frame` (so ToGlobal must undo it).
LocalMap MakeMap(const std::vector<Point2>& global, double dx, Pose2 frame, double travel) {
  LocalMap m;
  m.truth.global_frame = frame;
  m.truth.travel_start = travel;
  m.truth.travel_end = travel + 5;
  const Pose2 inv = Inverse(frame);
  for (const Point2& p : global) m.points.push_back(TransformPoint(inv, {p.x + dx, p.y}));
  m.trajectory.push_back({});
  return m;
}

std::vector<Point2> Corner() {  // an L of points every 0.1 m
  std::vector<Point2> pts;
  for (int i = 0; i < 50; ++i) pts.push_back({i * 0.1, 0.0});
  for (int i = 1; i < 50; ++i) pts.push_back({0.0, i * 0.1});
  return pts;
}

TEST(GroundTruth, ToGlobalUndoesTheOwnFrame) {
  const LocalMap m = MakeMap(Corner(), 0.0, {3, -2, 1.1}, 0);
  const std::vector<Point2> g = ToGlobal(m);
  ASSERT_EQ(g.size(), Corner().size());
  EXPECT_NEAR(g[7].x, 0.7, 1e-9);
  EXPECT_NEAR(g[7].y, 0.0, 1e-9);
}

TEST(GroundTruth, RelevantIsTheClosestCandidateBeyondTheTravelGap) {
  const std::vector<Point2> c = Corner();
  std::vector<LocalMap> maps;
  maps.push_back(MakeMap(c, 0.0, {0, 0, 0}, 0));       // 0: query
  maps.push_back(MakeMap(c, 0.0, {1, 1, 0.5}, 5));     // 1: identical but 5 m of travel away: not a candidate
  maps.push_back(MakeMap(c, 0.3, {2, 0, -1.0}, 20));   // 2: 0.3 m off
  maps.push_back(MakeMap(c, 0.1, {-4, 2, 2.0}, 40));   // 3: 0.1 m off -> relevant for 0
  maps.push_back(MakeMap(c, 50.0, {0, 0, 0}, 60));     // 4: elsewhere
  const std::vector<RelevantPair> pairs = FindRelevantPairs(maps);
  const RelevantPair* p0 = nullptr;
  for (const RelevantPair& p : pairs) {
    if (p.query == 0) p0 = &p;
    EXPECT_NE(p.query, 4u) << "map 4 revisits nothing";
    EXPECT_LT(p.mean_dist_m, 0.5);
  }
  ASSERT_NE(p0, nullptr);
  EXPECT_EQ(p0->relevant, 3u);
  // Points 1..49 along x are 0.1 away; along y the nearest shifted point is
  // (0.1, 0) for y < 0.1 ... mean is below 0.1.
  EXPECT_GT(p0->mean_dist_m, 0.05);
  EXPECT_LE(p0->mean_dist_m, 0.1 + 1e-6);
  EXPECT_EQ(p0->candidates, 3u);  // maps 2, 3, 4
  const std::vector<size_t> counts = CandidateCounts(maps);
  EXPECT_EQ(counts[0], 3u);
  EXPECT_EQ(counts[1], 3u);  // 5 m from 0 and 20 m is 15 away: 2, 3, 4
}

TEST(GroundTruth, QueriesWithoutACloseCandidateAreNotCounted) {
  const std::vector<Point2> c = Corner();
  std::vector<LocalMap> maps = {MakeMap(c, 0.0, {}, 0), MakeMap(c, 3.0, {}, 20)};
  EXPECT_TRUE(FindRelevantPairs(maps).empty());
  GroundTruthOptions loose;
  loose.max_mean_dist_m = 10.0;
  EXPECT_EQ(FindRelevantPairs(maps, loose).size(), 2u);
}

double BruteMean(const std::vector<Point2>& q, const std::vector<Point2>& db) {
  double sum = 0;
  for (const Point2& p : q) {
    double best = std::numeric_limits<double>::infinity();
    for (const Point2& d : db) best = std::min(best, (p.x - d.x) * (p.x - d.x) + (p.y - d.y) * (p.y - d.y));
    sum += std::sqrt(best);
  }
  return sum / q.size();
}

TEST(GroundTruth, DemoWorldHasLoopsAndAgreesWithBruteForce) {
  const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  const std::vector<RelevantPair> pairs = FindRelevantPairs(maps);
  EXPECT_GT(pairs.size(), maps.size() / 4) << "the demo route revisits places";
  size_t overlapping = 0;
  for (const RelevantPair& p : pairs) {
    EXPECT_GT(std::abs(maps[p.query].truth.travel_start - maps[p.relevant].truth.travel_start), 10.0);
    overlapping += PlaceOverlap(maps[p.query], maps[p.relevant]) >= 0.5 ? 1 : 0;
  }
  EXPECT_GT(overlapping, pairs.size() * 9 / 10);
  // Brute force on a few queries: the same relevant map and mean distance.
  std::vector<std::vector<Point2>> global;
  for (const LocalMap& m : maps) global.push_back(ToGlobal(m));
  for (size_t k = 0; k < pairs.size(); k += pairs.size() / 2 + 1) {
    const RelevantPair& p = pairs[k];
    double best = std::numeric_limits<double>::infinity();
    size_t best_j = 0;
    for (size_t j = 0; j < maps.size(); ++j) {
      if (std::abs(maps[j].truth.travel_start - maps[p.query].truth.travel_start) <= 10.0) continue;
      const double d = BruteMean(global[p.query], global[j]);
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    EXPECT_EQ(p.relevant, best_j);
    EXPECT_NEAR(p.mean_dist_m, best, 1e-5);
  }
}

TEST(GroundTruth, PlaceOverlapCountsQueryPointsNearTheDb) {
  const std::vector<Point2> c = Corner();
  std::vector<Point2> half(c.begin(), c.begin() + 50);  // the x arm only
  const LocalMap q = MakeMap(c, 0.0, {1, 2, 0.3}, 0);
  const LocalMap d = MakeMap(half, 0.0, {-1, 0, 2.0}, 0);
  // The x arm (50 points) and the y-arm points at 0.1, 0.2 (0.3 is on the
  // boundary: rounding decides) are within 0.3 m.
  const double overlap = PlaceOverlap(q, d);
  EXPECT_GE(overlap, 52.0 / 99.0 - 1e-9);
  EXPECT_LE(overlap, 53.0 / 99.0 + 1e-9);
  EXPECT_DOUBLE_EQ(PlaceOverlap(q, q), 1.0);
  EXPECT_DOUBLE_EQ(PlaceOverlap(LocalMap{}, q), 0.0);
}

TEST(GroundTruth, RealLogHasRevisitedPlaces) {
  const std::string path = std::string(LMD_SHARED_DATA_DIR) + "/fr101.log.gz";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "real log not found: " << path;
  auto log = ReadCarmenLog(path);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  const std::vector<LocalMap> maps = BuildLocalMaps(*log);
  const std::vector<RelevantPair> pairs = FindRelevantPairs(maps);
  EXPECT_GT(pairs.size(), maps.size() / 3);
}

}  // namespace
}  // namespace lmd
