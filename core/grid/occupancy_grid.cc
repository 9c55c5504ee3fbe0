#include "core/grid/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lmd {
namespace {

constexpr int64_t kMaxCells = 16 * 1024 * 1024;  // hard cap: 16 M cells

// Walks the cells crossed by the segment from `a` to `b` (grid axes, m),
// marking them free; the cell holding `b` is left alone when `stop_before_end`.
// Amanatides-Woo traversal, stops at the grid border. `cells` is the grid's
// row-major storage (the hot loop writes it directly: one beam crosses
// dozens of cells and a map has thousands of beams).
void TraceFree(const OccupancyGrid& grid, uint8_t* cells, double ax, double ay, double bx, double by,
               bool stop_before_end) {
  const double cell = grid.cell_m();
  const double gx = (ax - grid.min_x()) / cell, gy = (ay - grid.min_y()) / cell;
  const double ex = (bx - grid.min_x()) / cell, ey = (by - grid.min_y()) / cell;
  int ix = static_cast<int>(std::floor(gx)), iy = static_cast<int>(std::floor(gy));
  const int end_x = static_cast<int>(std::floor(ex)), end_y = static_cast<int>(std::floor(ey));
  if (!grid.Contains(ix, iy)) return;
  const double dx = ex - gx, dy = ey - gy;
  const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  const double t_dx = dx != 0 ? std::abs(1.0 / dx) : inf;
  const double t_dy = dy != 0 ? std::abs(1.0 / dy) : inf;
  double t_x = dx > 0 ? (ix + 1 - gx) * t_dx : dx < 0 ? (gx - ix) * t_dx : inf;
  double t_y = dy > 0 ? (iy + 1 - gy) * t_dy : dy < 0 ? (gy - iy) * t_dy : inf;
  const int width = grid.width(), height = grid.height();
  const long row_step = step_y > 0 ? width : -width;
  size_t k = static_cast<size_t>(iy) * width + ix;
  constexpr uint8_t kFree = static_cast<uint8_t>(CellState::kFree);
  // Next cell along the beam; false when it leaves the grid.
  auto step = [&] {
    if (t_x < t_y) {
      ix += step_x;
      if (ix < 0 || ix >= width) return false;
      k += step_x;
      t_x += t_dx;
    } else {
      iy += step_y;
      if (iy < 0 || iy >= height) return false;
      k += row_step;
      t_y += t_dy;
    }
    return true;
  };
  // Every step moves one cell towards the end cell (the directions are fixed),
  // so the beam can be in the end cell only after exactly `to_end` steps: no
  // test per cell before that.
  const int to_end = std::abs(end_x - ix) + std::abs(end_y - iy);
  for (int n = 0; n < to_end; ++n) {
    cells[k] = kFree;
    if (!step()) return;
  }
  if (ix == end_x && iy == end_y) {
    if (!stop_before_end) cells[k] = kFree;
    return;
  }
  // Rounding made the beam miss the end cell: two more cells, then stop.
  cells[k] = kFree;
  if (step()) cells[k] = kFree;
}

// Marks cells within radius of segment a-b (grid axes) free.
void StampSegment(OccupancyGrid& grid, double ax, double ay, double bx, double by, double radius) {
  const double cell = grid.cell_m();
  const int x0 = static_cast<int>(std::floor((std::min(ax, bx) - radius - grid.min_x()) / cell));
  const int x1 = static_cast<int>(std::floor((std::max(ax, bx) + radius - grid.min_x()) / cell));
  const int y0 = static_cast<int>(std::floor((std::min(ay, by) - radius - grid.min_y()) / cell));
  const int y1 = static_cast<int>(std::floor((std::max(ay, by) + radius - grid.min_y()) / cell));
  const double vx = bx - ax, vy = by - ay, len2 = vx * vx + vy * vy;
  for (int iy = std::max(0, y0); iy <= std::min(grid.height() - 1, y1); ++iy) {
    for (int ix = std::max(0, x0); ix <= std::min(grid.width() - 1, x1); ++ix) {
      const double cx = grid.min_x() + (ix + 0.5) * cell, cy = grid.min_y() + (iy + 0.5) * cell;
      double t = len2 > 0 ? ((cx - ax) * vx + (cy - ay) * vy) / len2 : 0.0;
      t = std::clamp(t, 0.0, 1.0);
      const double px = ax + t * vx - cx, py = ay + t * vy - cy;
      if (px * px + py * py <= radius * radius) grid.set(ix, iy, CellState::kFree);
    }
  }
}

}  // namespace

OccupancyGrid::OccupancyGrid(double rotation, double min_x, double min_y, double cell_m, int width, int height)
    : rotation_(rotation), min_x_(min_x), min_y_(min_y), cell_m_(cell_m), width_(std::max(width, 0)),
      height_(std::max(height, 0)),
      cells_(static_cast<size_t>(width_) * static_cast<size_t>(height_), static_cast<uint8_t>(CellState::kUnknown)) {}

Point2 OccupancyGrid::ToGrid(const Point2& p) const {
  const double c = std::cos(rotation_), s = std::sin(rotation_);
  return {c * p.x + s * p.y, -s * p.x + c * p.y};
}

Point2 OccupancyGrid::ToOwn(const Point2& g) const {
  const double c = std::cos(rotation_), s = std::sin(rotation_);
  return {c * g.x - s * g.y, s * g.x + c * g.y};
}

void OccupancyGrid::CellOf(const Point2& own, int* ix, int* iy) const {
  const Point2 g = ToGrid(own);
  *ix = static_cast<int>(std::floor((g.x - min_x_) / cell_m_));
  *iy = static_cast<int>(std::floor((g.y - min_y_) / cell_m_));
}

Point2 OccupancyGrid::CellCentre(int ix, int iy) const {
  return ToOwn({min_x_ + (ix + 0.5) * cell_m_, min_y_ + (iy + 0.5) * cell_m_});
}

size_t OccupancyGrid::Count(CellState s) const {
  return static_cast<size_t>(std::count(cells_.begin(), cells_.end(), static_cast<uint8_t>(s)));
}

OccupancyGrid BuildOccupancyGrid(const LocalMap& map, double rotation, const GridOptions& options) {
  const double cell = options.cell_m > 0 ? options.cell_m : 0.1;
  const double c = std::cos(rotation), s = std::sin(rotation);
  auto rot = [&](double x, double y) { return Point2{c * x + s * y, -s * x + c * y}; };
  const double inf = std::numeric_limits<double>::infinity();

  // Content box: points and trajectory, in grid axes.
  double lo_x = inf, lo_y = inf, hi_x = -inf, hi_y = -inf;
  auto grow = [&](const Point2& g) {
    if (!std::isfinite(g.x) || !std::isfinite(g.y)) return;
    lo_x = std::min(lo_x, g.x), hi_x = std::max(hi_x, g.x);
    lo_y = std::min(lo_y, g.y), hi_y = std::max(hi_y, g.y);
  };
  for (const Point2& p : map.points) grow(rot(p.x, p.y));
  double tlo_x = inf, tlo_y = inf, thi_x = -inf, thi_y = -inf;
  auto grow_traj = [&](double x, double y) {
    const Point2 g = rot(x, y);
    if (!std::isfinite(g.x) || !std::isfinite(g.y)) return;
    tlo_x = std::min(tlo_x, g.x), thi_x = std::max(thi_x, g.x);
    tlo_y = std::min(tlo_y, g.y), thi_y = std::max(thi_y, g.y);
  };
  for (const Pose2& p : map.trajectory) grow_traj(p.x, p.y);
  for (const Scan& sc : map.scans) grow_traj(sc.pose.x, sc.pose.y);
  if (tlo_x <= thi_x) {
    lo_x = std::min(lo_x, tlo_x), hi_x = std::max(hi_x, thi_x);
    lo_y = std::min(lo_y, tlo_y), hi_y = std::max(hi_y, thi_y);
    if (options.crop_m > 0) {
      lo_x = std::max(lo_x, tlo_x - options.crop_m), hi_x = std::min(hi_x, thi_x + options.crop_m);
      lo_y = std::max(lo_y, tlo_y - options.crop_m), hi_y = std::min(hi_y, thi_y + options.crop_m);
    }
  }
  if (!(lo_x <= hi_x && lo_y <= hi_y)) return OccupancyGrid(rotation, 0.0, 0.0, cell, 1, 1);

  const double margin = std::max(options.margin_m, 0.0) + cell;
  const double min_x = std::floor((lo_x - margin) / cell) * cell;
  const double min_y = std::floor((lo_y - margin) / cell) * cell;
  int64_t w = static_cast<int64_t>(std::ceil((hi_x + margin - min_x) / cell));
  int64_t h = static_cast<int64_t>(std::ceil((hi_y + margin - min_y) / cell));
  w = std::max<int64_t>(w, 1), h = std::max<int64_t>(h, 1);
  while (w * h > kMaxCells) {  // pathological extents: shrink symmetrically
    w = w * 9 / 10 + 1, h = h * 9 / 10 + 1;
  }
  OccupancyGrid grid(rotation, min_x, min_y, cell, static_cast<int>(w), static_cast<int>(h));

  if (!options.free_space) {
    // Occupied cells only (below).
  } else if (!map.scans.empty()) {
    uint8_t* cells = grid.mutable_cells();
    const Pose2* traced = nullptr;
    for (const Scan& sc : map.scans) {
      if (traced != nullptr &&
          std::hypot(sc.pose.x - traced->x, sc.pose.y - traced->y) < options.min_scan_spacing_m &&
          std::abs(std::remainder(sc.pose.theta - traced->theta, 2 * M_PI)) * 180 / M_PI < options.min_scan_turn_deg) {
        continue;
      }
      traced = &sc.pose;
      const Point2 o = rot(sc.pose.x, sc.pose.y);
      const double clear = std::min<double>(options.no_return_clear_m, sc.max_range);
      double last_fx = std::numeric_limits<double>::quiet_NaN(), last_fy = last_fx;
      bool last_hit = false;
      for (size_t i = 0; i < sc.ranges.size(); ++i) {
        const double r = sc.ranges[i];
        if (!(r > 0.0) || !std::isfinite(r)) continue;
        const bool hit = r < sc.max_range;
        const double len = hit ? r : clear;
        const double a = sc.pose.theta + sc.first_angle + static_cast<double>(i) * sc.angle_step - rotation;
        const double ex = o.x + len * std::cos(a), ey = o.y + len * std::sin(a);
        const double fx = std::floor((ex - min_x) / cell), fy = std::floor((ey - min_y) / cell);
        if (options.one_beam_per_end_cell && fx == last_fx && fy == last_fy && hit == last_hit) continue;
        last_fx = fx, last_fy = fy, last_hit = hit;
        TraceFree(grid, cells, o.x, o.y, ex, ey, hit);
      }
    }
  } else if (!map.trajectory.empty()) {
    for (size_t i = 0; i < map.trajectory.size(); ++i) {
      const Pose2& a = map.trajectory[i];
      const Pose2& b = map.trajectory[i + 1 < map.trajectory.size() ? i + 1 : i];
      const Point2 ga = rot(a.x, a.y), gb = rot(b.x, b.y);
      StampSegment(grid, ga.x, ga.y, gb.x, gb.y, options.trajectory_free_radius_m);
    }
  }
  for (const Point2& p : map.points) {
    const Point2 g = rot(p.x, p.y);
    if (!std::isfinite(g.x) || !std::isfinite(g.y)) continue;
    const double fx = std::floor((g.x - min_x) / cell), fy = std::floor((g.y - min_y) / cell);
    if (fx < 0 || fy < 0 || fx >= w || fy >= h) continue;
    grid.set(static_cast<int>(fx), static_cast<int>(fy), CellState::kOccupied);
  }
  return grid;
}

}  // namespace lmd
