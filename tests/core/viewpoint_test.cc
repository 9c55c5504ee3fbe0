#include "core/viewpoint/viewpoint.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/viewpoint/orientation.h"
#include "core/viewpoint/walls.h"
#include "tests/core/toy_world.h"

namespace lmd {
namespace {

double Deg(double rad) { return rad * 180.0 / M_PI; }

// Difference of two angles modulo 90 deg, in [0, 45] deg.
double DiffMod90Deg(double a_rad, double b_rad) {
  double d = std::fmod(Deg(a_rad - b_rad), 90.0);
  if (d < 0) d += 90.0;
  return std::min(d, 90.0 - d);
}

TEST(EntropyCompassTest, RotatingAMapMovesTheOrientationByTheSameAngleModulo90) {
  const LocalMap base = testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit());
  const double base_theta = EstimateDominantOrientation(base.points);
  EXPECT_LT(DiffMod90Deg(base_theta, 0.0), 1.0);  // the toy world is axis-aligned
  for (double deg : {3.3, 17.0, 29.9, 44.5, 45.5, 61.2, 89.7, 137.0, 212.4, -33.0}) {
    const LocalMap turned = testing::Transformed(base, {1.7, -0.4, deg * M_PI / 180.0});
    const double theta = EstimateDominantOrientation(turned.points);
    EXPECT_GE(theta, 0.0);
    EXPECT_LT(theta, M_PI / 2);
    EXPECT_LT(DiffMod90Deg(theta, base_theta + deg * M_PI / 180.0), 1.0) << "rotated by " << deg << " deg";
  }
}

// Points every 5 cm along a w x h rectangle's outline, turned by deg about (cx, cy).
std::vector<Point2> RectangleOutline(double cx, double cy, double w, double h, double deg) {
  const double c = std::cos(deg * M_PI / 180.0), s = std::sin(deg * M_PI / 180.0);
  std::vector<Point2> out;
  auto add = [&](double x, double y) { out.push_back({cx + c * x - s * y, cy + s * x + c * y}); };
  for (double t = -w / 2; t <= w / 2; t += 0.05) add(t, -h / 2), add(t, h / 2);
  for (double t = -h / 2; t <= h / 2; t += 0.05) add(-w / 2, t), add(w / 2, t);
  return out;
}

TEST(EntropyCompassTest, TheDirectionWithMoreWallWins) {
  // Two buildings turned 35 deg from each other: the coarse sweep sees a
  // peak for each, and the estimate follows the one with more wall, so that
  // neither peak wins by its position in the sweep.
  for (const bool first_is_bigger : {true, false}) {
    std::vector<Point2> points = RectangleOutline(0, 0, first_is_bigger ? 12 : 5, first_is_bigger ? 8 : 4, 20.0);
    for (const Point2& p : RectangleOutline(15, 3, first_is_bigger ? 5 : 12, first_is_bigger ? 4 : 8, 55.0)) {
      points.push_back(p);
    }
    const double want = first_is_bigger ? 20.0 : 55.0;
    EXPECT_LT(DiffMod90Deg(EstimateDominantOrientation(points), want * M_PI / 180.0), 1.0)
        << "bigger building at " << want << " deg";
  }
}

TEST(EntropyCompassTest, TooFewPointsGiveZero) {
  EXPECT_EQ(EstimateDominantOrientation({}), 0.0);
  EXPECT_EQ(EstimateDominantOrientation({{1, 2}}), 0.0);
}

TEST(WallPrimitiveTest, RoomWallsBecomeAxisAlignedRuns) {
  const LocalMap map = testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit());
  const OccupancyGrid grid = BuildOccupancyGrid(map, 0.0, {});
  const std::vector<WallPrimitive> walls = ExtractWalls(grid, {});
  double longest_h = 0, longest_v = 0;
  for (const WallPrimitive& w : walls) {
    const double len = ((w.x1 - w.x0) + (w.y1 - w.y0) + 1) * grid.cell_m();
    EXPECT_GE(len, 0.6 - 1e-9);
    (w.horizontal ? longest_h : longest_v) = std::max(w.horizontal ? longest_h : longest_v, len);
  }
  EXPECT_GT(longest_h, 5.5);   // the room's 6 m south / north walls
  EXPECT_GT(longest_v, 10.0);  // the corridor's sides
}

TEST(ViewpointTest, CogOfAClosedRoomIsItsCentre) {
  std::vector<testing::Wall> room = {{{0, 0}, {6, 0}}, {{6, 0}, {6, 4}}, {{6, 4}, {0, 4}}, {{0, 4}, {0, 0}}};
  std::vector<Pose2> poses;
  for (double t = 0; t < 2 * M_PI; t += M_PI / 4) poses.push_back({3, 2, t});
  const LocalMap map = testing::ScanWorld(room, poses);
  ViewpointOptions options;
  options.planner = Planner::kCoG;
  const ViewpointPlan plan = PlanViewpointDetailed(map, options);
  EXPECT_NEAR(plan.cog.origin.x, 3.0, 0.15);
  EXPECT_NEAR(plan.cog.origin.y, 2.0, 0.15);
  EXPECT_NEAR(plan.frame.origin.x, plan.cog.origin.x, 1e-12);
  // In a lone rectangular room the rooms peak is the room itself: CoR at its centre too.
  EXPECT_NEAR(plan.cor.origin.x, 3.0, 0.2);
  EXPECT_NEAR(plan.cor.origin.y, 2.0, 0.2);
}

TEST(ViewpointTest, CorOfARoomWithAnAlcoveLiesInTheRoom) {
  // A 6 x 6 m room with a door in its east wall onto a 2 x 2 m alcove: the
  // room dominates both room-cell histograms, so CoR is near its centre (3, 3).
  const std::vector<testing::Wall> walls = {
      {{0, 0}, {6, 0}}, {{0, 6}, {6, 6}}, {{0, 0}, {0, 6}}, {{6, 0}, {6, 2.5}}, {{6, 3.5}, {6, 6}},
      {{6, 2}, {8, 2}}, {{6, 4}, {8, 4}}, {{8, 2}, {8, 4}}};
  std::vector<Pose2> poses;
  for (double x = 7.5; x >= 2.5; x -= 0.5) poses.push_back({x, 3, M_PI});
  for (double t = M_PI; t <= 3 * M_PI; t += M_PI / 6) poses.push_back({2.5, 3, t});
  const LocalMap map = testing::ScanWorld(walls, poses);
  const ViewpointPlan plan = PlanViewpointDetailed(map, {});
  EXPECT_NEAR(plan.cor.origin.x, 3.0, 0.5);
  EXPECT_NEAR(plan.cor.origin.y, 3.0, 0.5);
  EXPECT_EQ(plan.room_cells.size(), plan.grid.cells().size());
  size_t peak = 0;
  for (uint8_t v : plan.room_peak) peak += v;
  EXPECT_GT(peak, 0u);
}

TEST(ViewpointTest, CorOfARoomOffALongCorridorFollowsTheHistogramPeaks) {
  // The paper's rule taken literally: the long corridor dominates f_x, the
  // room dominates f_y, so CoR lies in the corridor beside the room's rows.
  const LocalMap map = testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit());
  const ViewpointPlan plan = PlanViewpointDetailed(map, {});
  EXPECT_GT(plan.cor.origin.x, 6.0);
  EXPECT_LT(plan.cor.origin.x, 8.0);
  EXPECT_GT(plan.cor.origin.y, 0.0);
  EXPECT_LT(plan.cor.origin.y, 6.0);
}

TEST(ViewpointTest, PlannedViewpointDoesNotDependOnTheMapsOwnFrame) {
  const LocalMap base = testing::ScanWorld(testing::RoomAndCorridor(), testing::RoomVisit());
  const Pose2 t{-3.2, 5.1, 0.7};
  const LocalMap moved = testing::Transformed(base, t);
  for (Planner planner : {Planner::kCoG, Planner::kCoR}) {
    ViewpointOptions options;
    options.planner = planner;
    const Frame a = PlanViewpoint(base, options);
    const Frame b = PlanViewpoint(moved, options);
    // Bring b's origin back into base's frame.
    const double c = std::cos(-t.theta), s = std::sin(-t.theta);
    const double dx = b.origin.x - t.x, dy = b.origin.y - t.y;
    const Point2 back{c * dx - s * dy, s * dx + c * dy};
    EXPECT_LT(std::hypot(back.x - a.origin.x, back.y - a.origin.y), 0.35) << PlannerName(planner);
    EXPECT_LT(DiffMod90Deg(b.heading, a.heading + t.theta), 1.0);
  }
}

// PlanViewpoint skips the room search when the planner is CoG: same frames.
TEST(ViewpointTest, PlanViewpointGivesTheDetailedPlansFrame) {
  std::vector<testing::Wall> world = {{{0, 0}, {6, 0}}, {{6, 0}, {6, 4}}, {{6, 4}, {2, 4}}, {{0, 4}, {0, 0}},
                                      {{2, 4}, {2, 9}}, {{0, 4}, {0, 9}}};
  std::vector<Pose2> poses;
  for (double t = 0; t < 2 * M_PI; t += M_PI / 4) poses.push_back({3, 2, t + 0.2});
  for (double y = 4.5; y < 8.5; y += 1.0) poses.push_back({1, y, M_PI / 2});
  const LocalMap map = testing::ScanWorld(world, poses);
  for (Planner planner : {Planner::kCoG, Planner::kCoR}) {
    ViewpointOptions options;
    options.planner = planner;
    const Frame detailed = PlanViewpointDetailed(map, options).frame;
    const Frame plain = PlanViewpoint(map, options);
    EXPECT_EQ(plain.origin.x, detailed.origin.x) << PlannerName(planner);
    EXPECT_EQ(plain.origin.y, detailed.origin.y) << PlannerName(planner);
    EXPECT_EQ(plain.heading, detailed.heading) << PlannerName(planner);
  }
  ViewpointOptions cor;
  cor.planner = Planner::kCoR;
  const ViewpointPlan plan = PlanViewpointDetailed(map, cor);
  EXPECT_GT(std::hypot(plan.cor.origin.x - plan.cog.origin.x, plan.cor.origin.y - plan.cog.origin.y), 0.05)
      << "the planners should differ on this map, or the test proves nothing";
}

TEST(ViewpointTest, FrameTransformsInvertEachOther) {
  const Frame f{{1.5, -2.0}, 0.4};
  const Point2 p{3.0, 4.0};
  const Point2 q = ToFrame(f, p);
  const Point2 back = FromFrame(f, q);
  EXPECT_NEAR(back.x, p.x, 1e-12);
  EXPECT_NEAR(back.y, p.y, 1e-12);
  EXPECT_NEAR(std::hypot(q.x, q.y), std::hypot(p.x - 1.5, p.y + 2.0), 1e-12);
}

TEST(ViewpointTest, EmptyMapPlansTheOwnOrigin) {
  const Frame f = PlanViewpoint(LocalMap{}, {});
  EXPECT_EQ(f.origin.x, 0.0);
  EXPECT_EQ(f.origin.y, 0.0);
  EXPECT_EQ(f.heading, 0.0);
}

}  // namespace
}  // namespace lmd
