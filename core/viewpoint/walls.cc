#include "core/viewpoint/walls.h"

#include <algorithm>
#include <cmath>

namespace lmd {
namespace {

// Runs of occupied cells along one line of cells; `occupied(k)` for k in [0, n).
template <typename Occupied, typename Emit>
void Runs(int n, int min_cells, int max_gap, const Occupied& occupied, const Emit& emit) {
  int start = -1, last = -1;
  for (int k = 0; k <= n; ++k) {
    const bool occ = k < n && occupied(k);
    if (occ) {
      if (start < 0) start = k;
      last = k;
    } else if (start >= 0 && (k == n || k - last > max_gap)) {
      if (last - start + 1 >= min_cells) emit(start, last);
      start = -1;
    }
  }
}

}  // namespace

std::vector<WallPrimitive> ExtractWalls(const OccupancyGrid& grid, const WallOptions& options) {
  std::vector<WallPrimitive> walls;
  const int min_cells = std::max(1, static_cast<int>(std::ceil(options.min_length_m / grid.cell_m() - 1e-9)));
  const int gap = std::max(0, options.max_gap_cells);
  for (int y = 0; y < grid.height(); ++y) {
    Runs(grid.width(), min_cells, gap, [&](int x) { return grid.at(x, y) == CellState::kOccupied; },
         [&](int a, int b) { walls.push_back({true, a, y, b, y}); });
  }
  for (int x = 0; x < grid.width(); ++x) {
    Runs(grid.height(), min_cells, gap, [&](int y) { return grid.at(x, y) == CellState::kOccupied; },
         [&](int a, int b) { walls.push_back({false, x, a, x, b}); });
  }
  return walls;
}

}  // namespace lmd
