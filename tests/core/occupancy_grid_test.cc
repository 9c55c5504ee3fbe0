#include "core/grid/occupancy_grid.h"

#include <cmath>

#include <gtest/gtest.h>

namespace lmd {
namespace {

// One scan at the origin facing +x: beam 0 hits a point 3 m ahead, beam 1
// (pointing +y) has no return.
LocalMap OneBeamMap() {
  LocalMap map;
  map.trajectory = {{0, 0, 0}};
  Scan s;
  s.pose = {0.05, 0.05, 0};
  s.first_angle = 0;
  s.angle_step = static_cast<float>(M_PI / 2);
  s.max_range = 10;
  s.ranges = {3.0f, 10.0f};
  map.scans.push_back(s);
  map.points = {{3.05, 0.05}, {0.05, -2.0}, {1.0, 6.0}};
  return map;
}

TEST(OccupancyGridTest, RayCastingMarksFreeOccupiedAndUnknown) {
  const LocalMap map = OneBeamMap();
  GridOptions options;
  options.crop_m = 0;  // cover everything
  options.no_return_clear_m = 4.0;
  const OccupancyGrid grid = BuildOccupancyGrid(map, 0.0, options);
  auto state = [&](double x, double y) {
    int ix, iy;
    grid.CellOf({x, y}, &ix, &iy);
    return grid.at(ix, iy);
  };
  EXPECT_EQ(state(0.05, 0.05), CellState::kFree);
  EXPECT_EQ(state(1.55, 0.05), CellState::kFree);
  EXPECT_EQ(state(2.95, 0.05), CellState::kFree);
  EXPECT_EQ(state(3.05, 0.05), CellState::kOccupied);   // the return
  EXPECT_EQ(state(0.05, -2.0), CellState::kOccupied);   // a point no beam reached
  EXPECT_EQ(state(1.55, 1.55), CellState::kUnknown);    // between the beams
  EXPECT_EQ(state(0.05, 3.5), CellState::kFree);        // no-return beam clears...
  EXPECT_EQ(state(0.05, 4.5), CellState::kUnknown);     // ...up to no_return_clear_m only
  EXPECT_EQ(state(0.05, -1.0), CellState::kUnknown);    // behind the robot
  EXPECT_NEAR(grid.cell_m(), 0.1, 1e-12);
}

TEST(OccupancyGridTest, ABeamFreesTheCellsItCrossesUpToItsReturn) {
  // One beam at a time, at angles that cross cells diagonally; the map's
  // only points are corners beyond the beam's reach, so that the grid covers it.
  for (double angle_deg : {0.0, 17.0, 45.0, 100.0, 200.0, 301.0}) {
    for (bool hit : {true, false}) {
      LocalMap map;
      map.points = {{-3.5, -3.5}, {3.5, 3.5}};
      Scan s;
      s.pose = {0.03, 0.07, 0};
      s.first_angle = static_cast<float>(angle_deg * M_PI / 180);
      s.max_range = 10;
      s.ranges = {hit ? 2.34f : 10.0f};
      map.scans.push_back(s);
      GridOptions options;
      options.crop_m = 0;
      options.no_return_clear_m = 2.34;
      const OccupancyGrid grid = BuildOccupancyGrid(map, 0.0, options);
      int x0, y0, x1, y1;
      grid.CellOf({0.03, 0.07}, &x0, &y0);
      const double a = s.first_angle;
      grid.CellOf({0.03 + 2.34 * std::cos(a), 0.07 + 2.34 * std::sin(a)}, &x1, &y1);
      // A 4-connected path from the robot's cell to the return's: one cell per
      // step, the return's cell left unknown when the beam hit something there.
      const size_t path = static_cast<size_t>(std::abs(x1 - x0) + std::abs(y1 - y0)) + 1;
      SCOPED_TRACE(testing::Message() << angle_deg << " deg, hit " << hit);
      EXPECT_EQ(grid.Count(CellState::kFree), hit ? path - 1 : path);
      EXPECT_EQ(grid.at(x0, y0), CellState::kFree);
      EXPECT_EQ(grid.at(x1, y1), hit ? CellState::kUnknown : CellState::kFree);
    }
  }
}

// A scan close to the last traced one (position and heading) is not traced;
// one far enough in either is.
TEST(OccupancyGridTest, ScansCloseToATracedOneAreSkipped) {
  LocalMap map = OneBeamMap();
  Scan near = map.scans[0];
  near.pose = {0.05, -0.15, 0.0};     // 20 cm aside
  near.ranges = {10.0f, 1.0f};        // would clear along +x, a row below the first scan's beam
  Scan turned = near;
  turned.pose = {0.15, 0.05, -M_PI / 2};  // 10 cm from the first, turned: traced
  turned.ranges = {1.0f, 10.0f};          // clears 1 m along -y
  map.scans.push_back(near);
  map.scans.push_back(turned);
  GridOptions options;
  options.crop_m = 0;
  options.no_return_clear_m = 4.0;
  options.min_scan_spacing_m = 0.25;
  options.min_scan_turn_deg = 5.0;
  const OccupancyGrid grid = BuildOccupancyGrid(map, 0.0, options);
  auto state = [&](double x, double y) {
    int ix, iy;
    grid.CellOf({x, y}, &ix, &iy);
    return grid.at(ix, iy);
  };
  EXPECT_EQ(state(3.05, 0.05), CellState::kOccupied);  // the first scan's return stays
  EXPECT_EQ(state(0.15, -0.55), CellState::kFree);     // the turned scan was traced
  options.min_scan_spacing_m = 0.0;
  options.min_scan_turn_deg = 0.0;
  const OccupancyGrid every = BuildOccupancyGrid(map, 0.0, options);
  int ix, iy;
  every.CellOf({3.05, 0.05}, &ix, &iy);
  EXPECT_EQ(every.at(ix, iy), CellState::kOccupied);  // points are occupied either way
  every.CellOf({1.55, -0.15}, &ix, &iy);
  EXPECT_EQ(every.at(ix, iy), CellState::kFree);  // the near scan's beam, traced when every scan is
  EXPECT_NE(state(1.55, -0.15), CellState::kFree);
}

// Two beams of one scan that end in one cell: the first runs up a row
// early, the second stays in the origin's row to its end. With
// one_beam_per_end_cell the second is not traced, and the cells only it
// crosses stay unknown.
TEST(OccupancyGridTest, OneBeamPerEndCellTracesOneOfTheBeamsEndingInACell) {
  LocalMap map;
  map.trajectory = {{0, 0, 0}};
  Scan s;
  s.pose = {0.05, 0.05, 0};
  const double a0 = std::atan2(0.14, 1.96), a1 = std::atan2(0.051, 2.04);  // ends (2.01, 0.19), (2.09, 0.101)
  s.first_angle = static_cast<float>(a0);
  s.angle_step = static_cast<float>(a1 - a0);
  s.max_range = 10;
  s.ranges = {static_cast<float>(std::hypot(1.96, 0.14)), static_cast<float>(std::hypot(2.04, 0.051))};
  map.scans.push_back(s);
  map.points = {{2.01, 0.19}, {2.09, 0.101}};
  GridOptions options;
  options.crop_m = 0;
  auto state = [](const OccupancyGrid& grid, double x, double y) {
    int ix, iy;
    grid.CellOf({x, y}, &ix, &iy);
    return grid.at(ix, iy);
  };
  const OccupancyGrid both = BuildOccupancyGrid(map, 0.0, options);
  EXPECT_EQ(state(both, 1.55, 0.05), CellState::kFree);   // the second beam's row
  EXPECT_EQ(state(both, 1.55, 0.15), CellState::kFree);   // the first's
  options.one_beam_per_end_cell = true;
  const OccupancyGrid one = BuildOccupancyGrid(map, 0.0, options);
  EXPECT_EQ(state(one, 1.55, 0.05), CellState::kUnknown);
  EXPECT_EQ(state(one, 1.55, 0.15), CellState::kFree);
  EXPECT_EQ(state(one, 2.05, 0.15), CellState::kOccupied);  // the end cell, as before
  // A beam without a return is traced even where one with a return ended.
  map.scans[0].ranges[1] = 10.0f;
  options.no_return_clear_m = std::hypot(2.04, 0.051);
  const OccupancyGrid no_return = BuildOccupancyGrid(map, 0.0, options);
  EXPECT_EQ(state(no_return, 1.55, 0.05), CellState::kFree);
}

TEST(OccupancyGridTest, MapsWithoutScansAreFreeNearTheTrajectory) {
  LocalMap map;
  map.trajectory = {{0, 0, 0}, {4, 0, 0}};
  map.points = {{2, 2}};
  GridOptions options;
  options.trajectory_free_radius_m = 0.5;
  const OccupancyGrid grid = BuildOccupancyGrid(map, 0.0, options);
  auto state = [&](double x, double y) {
    int ix, iy;
    grid.CellOf({x, y}, &ix, &iy);
    return grid.at(ix, iy);
  };
  EXPECT_EQ(state(2.0, 0.0), CellState::kFree);
  EXPECT_EQ(state(2.0, 0.35), CellState::kFree);
  EXPECT_EQ(state(2.0, 1.0), CellState::kUnknown);
  EXPECT_EQ(state(2.0, 2.0), CellState::kOccupied);
  EXPECT_GT(grid.Count(CellState::kFree), 300u);
}

TEST(OccupancyGridTest, RotatedGridAxesFollowTheRotation) {
  LocalMap map;
  map.trajectory = {{0, 0, 0}};
  map.points = {{0, 2}};
  const OccupancyGrid grid = BuildOccupancyGrid(map, M_PI / 2, {});
  const Point2 g = grid.ToGrid({0, 2});
  EXPECT_NEAR(g.x, 2.0, 1e-9);  // own +y is grid +x after a 90 deg turn
  EXPECT_NEAR(g.y, 0.0, 1e-9);
  int ix, iy;
  grid.CellOf({0, 2}, &ix, &iy);
  EXPECT_EQ(grid.at(ix, iy), CellState::kOccupied);
  const Point2 back = grid.CellCentre(ix, iy);
  EXPECT_NEAR(back.x, 0.0, 0.08);
  EXPECT_NEAR(back.y, 2.0, 0.08);
}

TEST(OccupancyGridTest, EmptyMapGivesOneUnknownCell) {
  const OccupancyGrid grid = BuildOccupancyGrid(LocalMap{}, 0.0, {});
  EXPECT_EQ(grid.width(), 1);
  EXPECT_EQ(grid.height(), 1);
  EXPECT_EQ(grid.at(0, 0), CellState::kUnknown);
}

}  // namespace
}  // namespace lmd
