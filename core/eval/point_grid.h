// A static hash grid over 2D points for nearest-point queries (internal
// helper of ground truth). Points are stored sorted by cell; a flat
// open-addressing table maps a cell to its run of points.
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace lmd {

class PointGrid {
 public:
  PointGrid() = default;
  // Builds over `points` with square cells of cell_m metres.
  PointGrid(const std::vector<Point2>& points, double cell_m);

  bool empty() const { return xs_.empty(); }
  double cell() const { return cell_; }

  // Distance from p to the nearest stored point if it is below `limit`, else
  // `limit` (exact: searches rings of cells until no closer point can exist).
  double NearestDistance(const Point2& p, double limit) const;

  // Appends the points of the 3 x 3 cells around cell (cx, cy) (cell
  // indices = floor(coordinate / cell)). Any other point is at least one
  // cell size away from a point of cell (cx, cy).
  void GatherBlock(int64_t cx, int64_t cy, std::vector<Point2>* out) const;

  // True if some stored point is within `radius` (<= cell) of p.
  bool AnyWithin(const Point2& p, double radius) const;

 private:
  // Index range [begin, end) of cell (ix, iy) in xs_/ys_; begin == end if empty.
  void Cell(int64_t ix, int64_t iy, uint32_t* begin, uint32_t* end) const;

  double cell_ = 1.0;
  double ox_ = 0.0, oy_ = 0.0;          // offset subtracted before storing as float
  std::vector<float> xs_, ys_;          // points sorted by cell
  std::vector<uint64_t> keys_;          // table: cell key or ~0
  std::vector<uint32_t> begin_, end_;   // table: run of the key's points
};

}  // namespace lmd
