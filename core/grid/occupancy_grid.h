// Occupancy grid of a local map (DESIGN.md §1 "ViewpointPlanner"): square
// cells (0.1 m by default) that are occupied (a map point falls in them), free
// (a laser beam crossed them, or, for maps without scans, the robot passed
// near them) or unknown. The grid may be rotated: its axes are those of the
// map's own frame turned by `rotation`, so that Manhattan walls run along
// rows and columns once the dominant orientation is known.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace lmd {

enum class CellState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct GridOptions {
  double cell_m = 0.1;  // m, cell side (paper: 0.1)
  // m; the grid covers the trajectory's bounding box grown by this much (in
  // the rotated axes). Points and beams outside are clipped. Bounds memory and
  // time for long-range logs (80 m beams); 0 or less = cover all points.
  double crop_m = 12.0;
  double margin_m = 0.3;  // m of unknown border around the covered content
  // m; for maps without scans, cells within this distance of the trajectory
  // (segments between consecutive poses) are free.
  double trajectory_free_radius_m = 0.6;
  // Beams with no return (range >= max_range) clear up to this many metres
  // (or their max_range if smaller); beams with a return clear up to it.
  double no_return_clear_m = 30.0;
  // false: occupied cells only (everything else unknown), same extent. Walls
  // read only occupied cells, so a planner that needs no rooms skips the
  // ray casting, most of the grid's cost.
  bool free_space = true;
  // Free space is traced from a scan only once its pose is this far from the
  // last traced one, or turned this much (0: every scan). Scans a few cm
  // apart clear the same cells: a fast laser (fr079: 55 scans of 360 beams
  // per 5 m map, 11 times intel's rays) would otherwise cost that much more.
  double min_scan_spacing_m = 0.0;
  double min_scan_turn_deg = 0.0;
  // A beam that ends in the cell the last traced beam of its scan ended in,
  // with a return as that one had or without as it had none, is not traced:
  // both leave from the scan's origin, so it would clear nearly the same
  // cells (at most a few beside its path differ). A dense laser (0.25-0.5
  // deg) puts several beams in one cell within a few metres.
  bool one_beam_per_end_cell = false;
};

// A rotated, axis-aligned grid. Cell (ix, iy) covers, in grid axes,
// [min_x + ix*cell, min_x + (ix+1)*cell) x [min_y + iy*cell, ...). Grid axes:
// g = R(-rotation) * p for a point p of the map's own frame.
class OccupancyGrid {
 public:
  OccupancyGrid() = default;
  // An all-unknown grid of width x height cells.
  OccupancyGrid(double rotation, double min_x, double min_y, double cell_m, int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  double cell_m() const { return cell_m_; }
  double rotation() const { return rotation_; }
  double min_x() const { return min_x_; }
  double min_y() const { return min_y_; }

  bool Contains(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width_ && iy < height_; }
  // State of a cell; kUnknown outside the grid.
  CellState at(int ix, int iy) const {
    return Contains(ix, iy) ? static_cast<CellState>(cells_[static_cast<size_t>(iy) * width_ + ix])
                            : CellState::kUnknown;
  }
  void set(int ix, int iy, CellState s) {
    if (Contains(ix, iy)) cells_[static_cast<size_t>(iy) * width_ + ix] = static_cast<uint8_t>(s);
  }
  // Row-major cell states (index iy * width + ix).
  const std::vector<uint8_t>& cells() const { return cells_; }
  uint8_t* mutable_cells() { return cells_.data(); }

  // Own-frame point -> grid axes, and back.
  Point2 ToGrid(const Point2& own) const;
  Point2 ToOwn(const Point2& grid) const;
  // Cell holding an own-frame point (may be outside the grid: check Contains).
  void CellOf(const Point2& own, int* ix, int* iy) const;
  // Own-frame centre of a cell.
  Point2 CellCentre(int ix, int iy) const;

  size_t Count(CellState s) const;

 private:
  double rotation_ = 0.0;
  double min_x_ = 0.0, min_y_ = 0.0;
  double cell_m_ = 0.1;
  int width_ = 0, height_ = 0;
  std::vector<uint8_t> cells_;
};

// Rasterises `map` into a grid whose axes are the own frame turned by
// `rotation` (rad). Occupied = cells holding a point of map.points; free =
// cells crossed by a scan beam before its end point (DDA traversal; a beam
// with no return clears up to no_return_clear_m) or, when map.scans is empty,
// cells near the trajectory. Occupied wins over free. An empty map gives a
// 1 x 1 unknown grid.
OccupancyGrid BuildOccupancyGrid(const LocalMap& map, double rotation, const GridOptions& options = {});

}  // namespace lmd
