// "Room" cells of the CoR planner: axis-aligned rectangles of free cells
// grown from seed cells, and the histograms f_x, f_y of their cells.
#pragma once

#include <cstdint>
#include <vector>

#include "core/grid/occupancy_grid.h"

namespace lmd {

struct RoomOptions {
  int seed_stride = 3;            // one seed every this many cells per axis
  double min_area_m2 = 0.5;       // m^2; smaller rectangles are dropped
  double peak_fraction = 0.9;     // keep f_x, f_y > this * peak (paper: 0.9)
};

struct RoomCells {
  std::vector<uint8_t> room;      // per cell (row-major): inside some rectangle
  std::vector<uint8_t> peak;      // per cell: room cell kept by the peak rule
  std::vector<double> f_x, f_y;   // per column / row: rectangle-cell counts
  bool found = false;             // at least one peak cell
  Point2 centre_grid;             // centre of gravity of the peak cells (grid axes, m)
};

// Grows, from every seed_stride-th free cell, the maximal free rectangle
// (one cell at a time on each side in turn while the new strip is all free);
// f_x[ix] = sum over kept rectangles of their cells in column ix (f_y alike);
// peak cells = room cells with f_x > peak_fraction * max f_x and
// f_y > peak_fraction * max f_y. found = false if no rectangle or no peak cell.
RoomCells FindRoomCells(const OccupancyGrid& grid, const RoomOptions& options = {});

}  // namespace lmd
