#include "core/align/scan_match.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "core/align/correlative_search.h"
#include "core/eval/ground_truth.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd {
namespace {

const std::vector<LocalMap>& DemoMaps() {
  static const std::vector<LocalMap> maps = SimulateLocalMaps(DefaultDemoOptions());
  return maps;
}

// A map with plenty of structure: the demo map with the most points.
const LocalMap& RichMap() {
  const std::vector<LocalMap>& maps = DemoMaps();
  return *std::max_element(maps.begin(), maps.end(), [](const LocalMap& a, const LocalMap& b) {
    return a.points.size() < b.points.size();
  });
}

// The map's points seen from a frame placed at `pose` in its own frame: the
// pose of the returned map's own frame in `map`'s own frame is `pose`.
LocalMap MovedCopy(const LocalMap& map, const Pose2& pose) {
  LocalMap out;
  out.id = map.id + "-moved";
  const Pose2 inv = Inverse(pose);
  for (const Point2& p : map.points) out.points.push_back(TransformPoint(inv, p));
  return out;
}

double TranslationError(const Pose2& a, const Pose2& b) { return std::hypot(a.x - b.x, a.y - b.y); }
double AngleErrorDeg(const Pose2& a, const Pose2& b) {
  return std::abs(NormalizeAngle(a.theta - b.theta)) * 180.0 / M_PI;
}
double Deg(double d) { return d * M_PI / 180.0; }

const std::vector<Pose2>& KnownTransforms() {
  static const std::vector<Pose2> poses = {
      {3.0, 0.0, 0.0}, {0.0, -3.0, Deg(90)}, {1.5, 2.0, Deg(180)}, {-3.0, 1.0, Deg(-90)}, {0.4, -0.7, Deg(30)},
  };
  return poses;
}

TEST(ScanMatchTest, GuessFreeSearchRecoversKnownRigidTransforms) {
  const LocalMap& db = RichMap();
  const PreparedMap prepared = PrepareMap(db);
  for (const Pose2& truth : KnownTransforms()) {
    const ScanMatch m = MatchLocalMapsGlobal(PrepareQuery(MovedCopy(db, truth)), prepared);
    EXPECT_LT(TranslationError(m.pose, truth), 0.05) << truth.x << " " << truth.y << " " << truth.theta;
    EXPECT_LT(AngleErrorDeg(m.pose, truth), 0.5) << truth.theta;
    EXPECT_GT(m.score, 0.99);
    EXPECT_LT(m.inlier_rms_m, 0.01);
  }
}

TEST(ScanMatchTest, ConvergesFromAGuessOffByMetresAndDegrees) {
  const LocalMap& db = RichMap();
  const PreparedMap prepared = PrepareMap(db);
  ScanMatchOptions wide;
  wide.window_m = 2.0;
  wide.window_deg = 10.0;
  for (const Pose2& truth : KnownTransforms()) {
    const PreparedQuery query = PrepareQuery(MovedCopy(db, truth));
    const Pose2 bad{truth.x + 1.2, truth.y - 0.9, truth.theta + Deg(8)};  // 1.5 m, 8 deg off
    const ScanMatch m = MatchLocalMaps(query, prepared, {bad}, wide);
    EXPECT_LT(TranslationError(m.pose, truth), 0.05);
    EXPECT_LT(AngleErrorDeg(m.pose, truth), 0.5);
    EXPECT_EQ(m.guess, 0);
  }
}

TEST(ScanMatchTest, DefaultWindowCoversAGuessOffByAMetreAndDegrees) {
  const LocalMap& db = RichMap();
  const PreparedMap prepared = PrepareMap(db);
  for (const Pose2& truth : KnownTransforms()) {
    const PreparedQuery query = PrepareQuery(MovedCopy(db, truth));
    const Pose2 bad{truth.x - 0.7, truth.y + 0.6, truth.theta - Deg(2.5)};  // 0.9 m, 2.5 deg off (window 3 deg)
    const ScanMatch m = MatchLocalMaps(query, prepared, {bad});
    EXPECT_LT(TranslationError(m.pose, truth), 0.05);
    EXPECT_LT(AngleErrorDeg(m.pose, truth), 0.5);
  }
}

// A well-matching pair keeps ICP's pose, far finer than the search's
// lattice (0.2 m cells, ~0.5 deg steps), whatever the re-check threshold.
TEST(ScanMatchTest, AGoodMatchKeepsTheRefinedPoseNotTheLattice) {
  const LocalMap& db = RichMap();
  const PreparedMap prepared = PrepareMap(db);
  for (double recheck_below : {0.0, 0.5, 1.0}) {
    ScanMatchOptions options;
    options.recheck_below = recheck_below;
    for (const Pose2& truth : KnownTransforms()) {
      const PreparedQuery query = PrepareQuery(MovedCopy(db, truth), options);
      const Pose2 guess{truth.x + 0.37, truth.y - 0.23, truth.theta + Deg(1.3)};
      const ScanMatch m = MatchLocalMaps(query, prepared, {guess}, options);
      EXPECT_LT(TranslationError(m.pose, truth), 0.01) << recheck_below;
      EXPECT_LT(AngleErrorDeg(m.pose, truth), 0.1) << recheck_below;
      EXPECT_GT(m.score, 0.99);
    }
  }
}

TEST(ScanMatchTest, QuarterTurnsResolveAGuessOffBy90Degrees) {
  const LocalMap& db = RichMap();
  const Pose2 truth{1.0, -2.0, Deg(20)};
  const Pose2 turned{truth.x, truth.y, truth.theta + Deg(90)};
  // The guess's frame is turned about the query centroid's image, as two
  // Manhattan frames disagreeing by 90 deg would be: rotate about the centroid.
  const LocalMap query_map = MovedCopy(db, truth);
  const PreparedQuery query = PrepareQuery(query_map);
  const Point2 c = TransformPoint(truth, query.centroid);
  const Point2 rc = TransformPoint(turned, query.centroid);
  const Pose2 guess{turned.x + c.x - rc.x, turned.y + c.y - rc.y, turned.theta};
  const ScanMatch m = MatchLocalMaps(query_map, db, {guess});
  EXPECT_LT(TranslationError(m.pose, truth), 0.05);
  EXPECT_LT(AngleErrorDeg(m.pose, truth), 0.5);
}

// The demo world repeats rooms and corridors, so a different place can align
// well (guess-free scores up to ~0.8 there); what is pinned is that a place
// seen again outscores different places far more often than not.
TEST(ScanMatchTest, SamePlaceMostlyOutscoresDifferentPlaces) {
  const std::vector<LocalMap>& maps = DemoMaps();
  std::vector<double> same, different;
  for (size_t i = 0; i < maps.size() && (same.size() < 8 || different.size() < 8); i += 7) {
    for (size_t j = i + 15; j < maps.size(); j += 11) {
      const double overlap = PlaceOverlap(maps[i], maps[j]);
      const bool want_same = overlap >= 0.5 && same.size() < 8;
      const bool want_different = overlap == 0.0 && different.size() < 8;
      if (!want_same && !want_different) continue;
      const ScanMatch m = MatchLocalMapsGlobal(PrepareQuery(maps[i]), PrepareMap(maps[j]));
      (want_same ? same : different).push_back(m.score);
      break;
    }
  }
  ASSERT_EQ(same.size(), 8u);
  ASSERT_EQ(different.size(), 8u);
  int wins = 0;
  for (double s : same) {
    for (double d : different) wins += s > d;
  }
  EXPECT_GE(wins, 40);  // of 64 (same, different) comparisons
  std::sort(same.begin(), same.end());
  EXPECT_GE(same.front(), 0.5);  // a place seen again always aligns with at least its overlap
}

TEST(ScanMatchTest, DegenerateInputsScoreZeroWithoutCrashing) {
  const LocalMap& rich = RichMap();
  LocalMap empty;
  LocalMap one;
  one.points = {{1.0, 2.0}};
  LocalMap not_finite;
  not_finite.points = {{NAN, 1.0}, {INFINITY, 0.0}};
  const Pose2 guess{0.5, 0.5, 0.1};
  const std::vector<const LocalMap*> inputs = {&empty, &one, &not_finite, &rich};
  for (const LocalMap* q : inputs) {
    for (const LocalMap* d : inputs) {
      if (q == &rich && d == &rich) continue;
      const ScanMatch guided = MatchLocalMaps(*q, *d, {guess});
      EXPECT_EQ(guided.score, 0.0);
      EXPECT_DOUBLE_EQ(guided.pose.x, guess.x);
      EXPECT_EQ(MatchLocalMaps(*q, *d, {}).score, 0.0);
      EXPECT_EQ(MatchLocalMapsGlobal(PrepareQuery(*q), PrepareMap(*d)).score, 0.0);
    }
  }
  EXPECT_EQ(SecondBestMatch(PrepareQuery(one), PrepareMap(rich), guess, 1.0, 10.0).score, 0.0);
}

// A query point's credit falls by thirds of the radius: 1 within 0.1 m of
// a map point, 2/3 within 0.2 m, 1/3 within 0.3 m, none beyond; the share
// counts each point within the radius alike.
TEST(ScanMatchTest, ClosenessCreditsEachPointByHowNearItsMapPointIs) {
  LocalMap wall;
  for (int i = 0; i <= 200; ++i) wall.points.push_back({0.05 * i, 0.0});
  const PreparedMap db = PrepareMap(wall);
  const std::vector<Point2> query = {{1.0, 0.05}, {3.0, 0.15}, {5.0, 0.25}, {7.0, 0.35}};
  const Overlap o = MeasureOverlap(query, db, {0, 0, 0}, 0.3);
  EXPECT_EQ(o.inliers, 3u);
  EXPECT_DOUBLE_EQ(o.fraction, 0.75);
  EXPECT_NEAR(o.closeness, (1.0 + 2.0 / 3 + 1.0 / 3) / 4, 1e-12);
  // Moved 6 cm toward the wall: 1 cm, 9 cm, 19 cm and 29 cm from it.
  const Overlap on = MeasureOverlap(query, db, {0, -0.06, 0}, 0.3);
  EXPECT_NEAR(on.closeness, (1.0 + 1.0 + 2.0 / 3 + 1.0 / 3) / 4, 1e-12);
  EXPECT_DOUBLE_EQ(on.fraction, 1.0);
  EXPECT_EQ(MeasureOverlap({}, db, {0, 0, 0}, 0.3).closeness, 0.0);
}

// A map made of two identical rooms 10 m apart: the query (one room) fits
// at two poses; the second-best search, away from the first, finds the
// other room, and never returns a pose inside the excluded zone.
TEST(ScanMatchTest, SecondBestMatchFindsTheLookAlikePoseAwayFromTheBest) {
  auto room = [](double x0, std::vector<Point2>* points) {
    for (double t = 0; t <= 4.0; t += 0.05) {
      points->push_back({x0 + t, 0.0});
      points->push_back({x0 + t, 3.0});
    }
    for (double t = 0; t <= 3.0; t += 0.05) {
      if (t < 1.0 || t > 2.0) points->push_back({x0, t});  // a door on the left
      points->push_back({x0 + 4.0, t});
    }
    for (double t = 0; t <= 1.0; t += 0.05) points->push_back({x0 + 1.0 + t, 1.5});  // a shelf
  };
  LocalMap two_rooms, one_room;
  room(0.0, &two_rooms.points);
  room(10.0, &two_rooms.points);
  room(0.0, &one_room.points);
  const PreparedMap db = PrepareMap(two_rooms);
  const PreparedQuery query = PrepareQuery(one_room);
  const ScanMatch best = MatchLocalMaps(query, db, {Pose2{0.2, 0.1, 0.0}});
  ASSERT_GT(best.score, 0.9);
  const ScanMatch second = SecondBestMatch(query, db, best.pose, 1.0, 10.0);
  EXPECT_GT(second.score, 0.9);
  const Point2 at = TransformPoint(second.pose, query.centroid), best_at = TransformPoint(best.pose, query.centroid);
  EXPECT_NEAR(std::hypot(at.x - best_at.x, at.y - best_at.y), 10.0, 0.3);

  // One room with an inner wall along one side: its other poses (the room
  // turned by a half turn) leave that wall unexplained.
  for (double t = 0; t <= 2.5; t += 0.05) one_room.points.push_back({0.5 + t, 2.3});
  const PreparedMap single = PrepareMap(one_room);
  const PreparedQuery walled = PrepareQuery(one_room);
  const ScanMatch alone = MatchLocalMaps(walled, single, {Pose2{0.2, 0.1, 0.0}});
  ASSERT_GT(alone.score, 0.95);
  EXPECT_LT(SecondBestMatch(walled, single, alone.pose, 1.0, 10.0).score, alone.score - 0.1);
}

// Branch and bound must return the lattice's exact best: compare with every
// lattice pose searched alone (zero-width regions at the same lattice points).
TEST(ScanMatchTest, CorrelativeSearchFindsTheExhaustiveBest) {
  const PreparedMap db = PrepareMap(DemoMaps()[40]);
  const PreparedQuery query = PrepareQuery(MovedCopy(DemoMaps()[43], {0.3, -0.2, Deg(2)}));
  CorrelativeOptions exact;
  exact.min_score = 0.0;  // always report the best, however poor
  const double cell = db.options.cell_m;
  const Point2 target{query.centroid.x + 0.37, query.centroid.y - 0.21};  // off the true pose
  for (double theta : {0.0, Deg(3), Deg(-2)}) {
    SearchRegion region;
    region.theta = theta;
    region.centroid_target = target;
    region.half_window_x_m = region.half_window_y_m = 1.0;
    const CorrelativeResult searched = CorrelativeSearch(query.search_points, db, {region}, exact);
    ASSERT_TRUE(searched.found);
    double best = 0.0;
    for (int dx = -5; dx <= 5; ++dx) {
      for (int dy = -5; dy <= 5; ++dy) {
        SearchRegion one;
        one.theta = theta;
        one.centroid_target = {target.x + dx * cell, target.y + dy * cell};
        best = std::max(best, CorrelativeSearch(query.search_points, db, {one}, exact).score);
      }
    }
    EXPECT_NEAR(searched.score, best, 0.005) << theta;
  }
}

// A search whose stop turns true gives up soon after (a caller's deadline),
// finding nothing; one whose stop stays false finds what it finds without one.
TEST(ScanMatchTest, CorrelativeSearchGivesUpWhenItsStopTurnsTrue) {
  const PreparedMap db = PrepareMap(DemoMaps()[40]);
  const PreparedQuery query = PrepareQuery(MovedCopy(DemoMaps()[43], {0.3, -0.2, Deg(2)}));
  SearchRegion wide;  // every turn over a wide window: thousands of blocks
  wide.half_window_rad = M_PI;
  wide.centroid_target = query.centroid;
  wide.half_window_x_m = wide.half_window_y_m = 8.0;
  CorrelativeOptions exact;
  exact.min_score = 0.0;
  const CorrelativeResult unbounded = CorrelativeSearch(query.search_points, db, {wide}, exact);
  ASSERT_TRUE(unbounded.found);

  CorrelativeOptions never = exact;
  size_t never_polls = 0;
  never.stop = [&] { return ++never_polls, false; };
  const CorrelativeResult same = CorrelativeSearch(query.search_points, db, {wide}, never);
  EXPECT_GT(never_polls, 0u);
  EXPECT_EQ(same.score, unbounded.score);
  EXPECT_EQ(same.evaluations, unbounded.evaluations);

  for (size_t stop_at : {size_t{1}, size_t{3}}) {
    CorrelativeOptions stopping = exact;
    size_t polls = 0;
    stopping.stop = [&] { return ++polls >= stop_at; };
    const CorrelativeResult given_up = CorrelativeSearch(query.search_points, db, {wide}, stopping);
    EXPECT_FALSE(given_up.found) << stop_at;
    EXPECT_EQ(given_up.score, 0.0) << stop_at;
    EXPECT_EQ(polls, stop_at) << "polled again after it said stop";
  }
}

// A bound from finer blocks is still a bound (>= the search's best over the
// window at that angle) and never looser than the coarsest level's.
TEST(ScanMatchTest, CorrelativeBoundFromFinerBlocksStillBoundsTheSearch) {
  const PreparedQuery query = PrepareQuery(MovedCopy(DemoMaps()[43], {0.3, -0.2, Deg(2)}));
  CorrelativeOptions exact;
  exact.min_score = 0.0;
  size_t tighter = 0;
  for (size_t db_index : {40, 43, 10, 70}) {
    const PreparedMap db = PrepareMap(DemoMaps()[db_index]);
    SearchRegion region;
    region.centroid_target = {query.centroid.x + 0.4, query.centroid.y - 0.3};
    region.half_window_x_m = region.half_window_y_m = 4.5;
    const double best = CorrelativeSearch(query.search_points, db, {region}, exact).score;
    const double coarse = CorrelativeBound(query.search_points, db, region);
    const double fine = CorrelativeBound(query.search_points, db, region, 1.6);
    EXPECT_GE(fine + 1e-9, best) << db_index;
    EXPECT_LE(fine, coarse + 1e-9) << db_index;
    tighter += fine < coarse - 0.01;
  }
  EXPECT_GE(tighter, 1u);  // the finer blocks tell something the coarsest did not
}

std::vector<double> Flat(const std::vector<Point2>& points) {
  std::vector<double> flat;
  for (const Point2& p : points) flat.insert(flat.end(), {p.x, p.y});
  return flat;
}

// A map gridded for a coarse fit (PrepareSearchGrid, a level built) and
// completed later is PrepareMap's, down to the pyramid, which it shares.
TEST(ScanMatchTest, ACompletedSearchGridIsThePreparedMap) {
  const LocalMap& db = RichMap();
  ASSERT_FALSE(db.scans.empty());
  const PreparedMapOptions options;
  const PreparedMap full = PrepareMap(db, options, 0.3);
  const PreparedMap grid = PrepareSearchGrid(db.points, options);
  ASSERT_TRUE(grid.SearchGridOnly());
  const LikelihoodLevel* fit_level = &grid.level(1);
  const PreparedMap done = CompletePreparation(grid, db, 0.3);
  EXPECT_FALSE(done.SearchGridOnly());
  EXPECT_EQ(&done.level(1), fit_level);
  EXPECT_EQ(done.heading, full.heading);
  EXPECT_EQ(Flat(done.points), Flat(full.points));
  EXPECT_EQ(Flat(done.sparse_points), Flat(full.sparse_points));
  EXPECT_EQ(Flat(done.normals), Flat(full.normals));
  EXPECT_EQ(done.bucket_start, full.bucket_start);
  EXPECT_GT(done.occupancy.Count(CellState::kFree), 0u);
  EXPECT_EQ(done.occupancy.cells(), full.occupancy.cells());
  EXPECT_EQ(done.MemoryBytes(), full.MemoryBytes());
  for (int h = 0; h < options.levels; ++h) EXPECT_EQ(done.level(h).values, full.level(h).values) << h;
}

TEST(ScanMatchTest, PreparedMapPyramidBoundsEveryFinerLevel) {
  const PreparedMap m = PrepareMap(RichMap());
  ASSERT_GE(m.options.levels, 2);
  // Level h at (x, y) is the max of level 0 over the 2^h block starting there.
  const LikelihoodLevel& l0 = m.level(0);
  for (int h = 1; h < m.options.levels; ++h) {
    const LikelihoodLevel& lh = m.level(h);
    const int block = 1 << h;
    for (int y = -lh.pad; y < lh.height - lh.pad; y += 7) {
      for (int x = -lh.pad; x < lh.width - lh.pad; x += 5) {
        uint8_t expect = 0;
        for (int by = y; by < y + block; ++by) {
          for (int bx = x; bx < x + block; ++bx) {
            if (bx >= 0 && by >= 0 && bx < l0.width && by < l0.height) {
              expect = std::max(expect, l0.values[static_cast<size_t>(by) * l0.width + bx]);
            }
          }
        }
        ASSERT_EQ(lh.values[static_cast<size_t>(y + lh.pad) * lh.width + x + lh.pad], expect) << h << " " << x << " " << y;
      }
    }
  }
}

// lmdd passes a stored map's planned heading to PrepareMap / PrepareQuery
// instead of recomputing it: both must be the same entropy compass.
TEST(PreparedMapTest, PlannedHeadingIsThePreparedHeading) {
  const std::vector<LocalMap>& maps = DemoMaps();
  for (size_t i = 0; i < maps.size(); i += 37) {
    const double planned = PlanViewpoint(maps[i]).heading;
    EXPECT_EQ(PrepareMap(maps[i]).heading, planned) << maps[i].id;
    EXPECT_EQ(PrepareQuery(maps[i]).heading, planned) << maps[i].id;
    EXPECT_EQ(PrepareMap(maps[i], {}, planned).heading, planned);
  }
}

}  // namespace
}  // namespace lmd
