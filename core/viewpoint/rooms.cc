#include "core/viewpoint/rooms.h"

#include <algorithm>
#include <cmath>

namespace lmd {

RoomCells FindRoomCells(const OccupancyGrid& grid, const RoomOptions& options) {
  const int w = grid.width(), h = grid.height();
  RoomCells out;
  const size_t n = static_cast<size_t>(w) * static_cast<size_t>(h);
  out.room.assign(n, 0);
  out.peak.assign(n, 0);
  out.f_x.assign(static_cast<size_t>(w), 0.0);
  out.f_y.assign(static_cast<size_t>(h), 0.0);
  if (n == 0) return out;

  // Summed-area table of NON-free cells: a strip is all free iff its sum is 0.
  const size_t sw = static_cast<size_t>(w) + 1;
  std::vector<int32_t> sat(sw * (static_cast<size_t>(h) + 1), 0);
  const auto& cells = grid.cells();
  for (int y = 0; y < h; ++y) {
    int32_t row = 0;
    for (int x = 0; x < w; ++x) {
      row += cells[static_cast<size_t>(y) * w + x] != static_cast<uint8_t>(CellState::kFree);
      sat[(y + 1) * sw + x + 1] = sat[y * sw + x + 1] + row;
    }
  }
  auto blocked = [&](int x0, int y0, int x1, int y1) {  // inclusive box
    return sat[(y1 + 1) * sw + x1 + 1] - sat[y0 * sw + x1 + 1] - sat[(y1 + 1) * sw + x0] + sat[y0 * sw + x0] != 0;
  };

  // Difference array for the union of rectangles.
  std::vector<int32_t> diff((static_cast<size_t>(w) + 1) * (static_cast<size_t>(h) + 1), 0);
  const double cell_area = grid.cell_m() * grid.cell_m();
  const int stride = std::max(1, options.seed_stride);
  bool any = false;
  for (int sy = stride / 2; sy < h; sy += stride) {
    for (int sx = stride / 2; sx < w; sx += stride) {
      if (cells[static_cast<size_t>(sy) * w + sx] != static_cast<uint8_t>(CellState::kFree)) continue;
      int x0 = sx, x1 = sx, y0 = sy, y1 = sy;
      for (bool grew = true; grew;) {
        grew = false;
        if (x0 > 0 && !blocked(x0 - 1, y0, x0 - 1, y1)) --x0, grew = true;
        if (x1 + 1 < w && !blocked(x1 + 1, y0, x1 + 1, y1)) ++x1, grew = true;
        if (y0 > 0 && !blocked(x0, y0 - 1, x1, y0 - 1)) --y0, grew = true;
        if (y1 + 1 < h && !blocked(x0, y1 + 1, x1, y1 + 1)) ++y1, grew = true;
      }
      const int rw = x1 - x0 + 1, rh = y1 - y0 + 1;
      if (rw * rh * cell_area < options.min_area_m2) continue;
      any = true;
      for (int x = x0; x <= x1; ++x) out.f_x[x] += rh;
      for (int y = y0; y <= y1; ++y) out.f_y[y] += rw;
      diff[y0 * sw + x0] += 1;
      diff[y0 * sw + x1 + 1] -= 1;
      diff[(y1 + 1) * sw + x0] -= 1;
      diff[(y1 + 1) * sw + x1 + 1] += 1;
    }
  }
  if (!any) return out;
  // Prefix sums of the difference array give the cover count of each cell.
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int32_t v = diff[y * sw + x];
      if (x > 0) v += diff[y * sw + x - 1];
      if (y > 0) v += diff[(y - 1) * sw + x];
      if (x > 0 && y > 0) v -= diff[(y - 1) * sw + x - 1];
      diff[y * sw + x] = v;
      out.room[static_cast<size_t>(y) * w + x] = v > 0;
    }
  }
  const double tx = options.peak_fraction * *std::max_element(out.f_x.begin(), out.f_x.end());
  const double ty = options.peak_fraction * *std::max_element(out.f_y.begin(), out.f_y.end());
  double sx = 0, sy = 0, cnt = 0;
  for (int y = 0; y < h; ++y) {
    if (!(out.f_y[y] > ty)) continue;
    for (int x = 0; x < w; ++x) {
      if (!(out.f_x[x] > tx) || !out.room[static_cast<size_t>(y) * w + x]) continue;
      out.peak[static_cast<size_t>(y) * w + x] = 1;
      sx += x + 0.5, sy += y + 0.5, cnt += 1;
    }
  }
  if (cnt == 0) return out;
  out.found = true;
  out.centre_grid = {grid.min_x() + sx / cnt * grid.cell_m(), grid.min_y() + sy / cnt * grid.cell_m()};
  return out;
}

}  // namespace lmd
