#include "core/viewpoint/viewpoint.h"

#include <cmath>

#include "core/viewpoint/rooms.h"

namespace lmd {

const char* PlannerName(Planner planner) { return planner == Planner::kCoG ? "cog" : "cor"; }

Point2 ToFrame(const Frame& frame, const Point2& p) {
  const double c = std::cos(frame.heading), s = std::sin(frame.heading);
  const double dx = p.x - frame.origin.x, dy = p.y - frame.origin.y;
  return {c * dx + s * dy, -s * dx + c * dy};
}

Point2 FromFrame(const Frame& frame, const Point2& q) {
  const double c = std::cos(frame.heading), s = std::sin(frame.heading);
  return {frame.origin.x + c * q.x - s * q.y, frame.origin.y + s * q.x + c * q.y};
}

namespace {

// Both planners' frames, or (with_rooms false) CoG only: CoR's room search
// and the free space it needs cost most of planning, and lmdd's CoG store
// never reads them. The grid then holds occupied cells only.
ViewpointPlan Plan(const LocalMap& map, const ViewpointOptions& options, bool with_rooms,
                   std::optional<double> known_heading) {
  ViewpointPlan plan;
  if (map.points.empty()) {
    plan.grid = BuildOccupancyGrid(map, 0.0, options.grid);
    plan.room_cells.assign(plan.grid.cells().size(), 0);
    plan.room_peak.assign(plan.grid.cells().size(), 0);
    return plan;
  }
  const double heading = known_heading ? *known_heading : EstimateDominantOrientation(map.points, options.orientation);
  GridOptions grid_options = options.grid;
  grid_options.free_space = grid_options.free_space && with_rooms;  // CoG reads only occupied cells
  plan.grid = BuildOccupancyGrid(map, heading, grid_options);
  const OccupancyGrid& grid = plan.grid;
  plan.walls = ExtractWalls(grid, options.walls);

  // CoG: centre of gravity of the union of wall cells.
  std::vector<uint8_t> wall_cell(grid.cells().size(), 0);
  double sx = 0, sy = 0, cnt = 0;
  for (const WallPrimitive& wp : plan.walls) {
    for (int y = wp.y0; y <= wp.y1; ++y) {
      for (int x = wp.x0; x <= wp.x1; ++x) {
        uint8_t& m = wall_cell[static_cast<size_t>(y) * grid.width() + x];
        if (m) continue;
        m = 1;
        sx += x + 0.5, sy += y + 0.5, cnt += 1;
      }
    }
  }
  Point2 cog;
  if (cnt > 0) {
    cog = grid.ToOwn({grid.min_x() + sx / cnt * grid.cell_m(), grid.min_y() + sy / cnt * grid.cell_m()});
  } else {
    for (const Point2& p : map.points) cog.x += p.x, cog.y += p.y;
    cog.x /= static_cast<double>(map.points.size()), cog.y /= static_cast<double>(map.points.size());
  }

  plan.cog = {cog, heading};
  plan.cor = plan.cog;
  if (!with_rooms) {
    plan.frame = plan.cog;
    return plan;
  }
  // CoR: centre of the peak room cells.
  RoomOptions room_options;
  room_options.seed_stride = options.room_seed_stride;
  room_options.min_area_m2 = options.room_min_area_m2;
  room_options.peak_fraction = options.room_peak_fraction;
  RoomCells rooms = FindRoomCells(grid, room_options);
  const Point2 cor = rooms.found ? grid.ToOwn(rooms.centre_grid) : cog;
  plan.room_cells = std::move(rooms.room);
  plan.room_peak = std::move(rooms.peak);

  plan.cor = {cor, heading};
  plan.frame = options.planner == Planner::kCoG ? plan.cog : plan.cor;
  return plan;
}

}  // namespace

ViewpointPlan PlanViewpointDetailed(const LocalMap& map, const ViewpointOptions& options) {
  return Plan(map, options, true, std::nullopt);
}

Frame PlanViewpoint(const LocalMap& map, const ViewpointOptions& options, std::optional<double> known_heading) {
  return Plan(map, options, options.planner == Planner::kCoR, known_heading).frame;
}

}  // namespace lmd
