// Axis-aligned wall primitives (Manhattan grammar): runs of occupied cells
// along the rows and columns of an occupancy grid whose axes follow the
// dominant orientation.
#pragma once

#include <vector>

#include "core/grid/occupancy_grid.h"

namespace lmd {

struct WallOptions {
  double min_length_m = 0.6;  // m; shorter runs are not walls
  int max_gap_cells = 1;      // unknown/free cells tolerated inside a run
};

// One wall primitive, in grid cells: cells (x0..x1, y) if horizontal, else
// (x, y0..y1) with x = x0 = x1. Ends inclusive.
struct WallPrimitive {
  bool horizontal = true;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// All horizontal runs (along rows) then vertical runs (along columns) of
// occupied cells at least min_length_m long, gaps of at most max_gap_cells
// bridged. A cell may belong to one horizontal and one vertical wall.
std::vector<WallPrimitive> ExtractWalls(const OccupancyGrid& grid, const WallOptions& options = {});

}  // namespace lmd
