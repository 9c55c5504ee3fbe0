#include "core/sim/world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace lmd {

World::World(std::vector<Segment> walls, std::vector<BuildingLayout> buildings, double cell_m)
    : walls_(std::move(walls)), buildings_(std::move(buildings)), cell_m_(cell_m > 0 ? cell_m : 1.0) {
  if (walls_.empty()) return;
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  for (const Segment& s : walls_) {
    min_x = std::min({min_x, s.a.x, s.b.x});
    min_y = std::min({min_y, s.a.y, s.b.y});
    max_x = std::max({max_x, s.a.x, s.b.x});
    max_y = std::max({max_y, s.a.y, s.b.y});
  }
  min_x_ = min_x - 0.5 * cell_m_;
  min_y_ = min_y - 0.5 * cell_m_;
  nx_ = static_cast<int>(std::floor((max_x + 0.5 * cell_m_ - min_x_) / cell_m_)) + 1;
  ny_ = static_cast<int>(std::floor((max_y + 0.5 * cell_m_ - min_y_) / cell_m_)) + 1;
  const size_t cells = static_cast<size_t>(nx_) * static_cast<size_t>(ny_);
  // Each wall goes into every cell of its bounding box (walls are short or
  // axis-aligned, so this stays tight). Two passes: count, then fill (CSR).
  auto cell_range = [&](const Segment& s, int* x0, int* x1, int* y0, int* y1) {
    *x0 = static_cast<int>(std::floor((std::min(s.a.x, s.b.x) - min_x_) / cell_m_));
    *x1 = static_cast<int>(std::floor((std::max(s.a.x, s.b.x) - min_x_) / cell_m_));
    *y0 = static_cast<int>(std::floor((std::min(s.a.y, s.b.y) - min_y_) / cell_m_));
    *y1 = static_cast<int>(std::floor((std::max(s.a.y, s.b.y) - min_y_) / cell_m_));
  };
  cell_start_.assign(cells + 1, 0);
  for (const Segment& s : walls_) {
    int x0, x1, y0, y1;
    cell_range(s, &x0, &x1, &y0, &y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++cell_start_[static_cast<size_t>(y) * nx_ + x + 1];
  }
  for (size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_walls_.resize(cell_start_[cells]);
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < walls_.size(); ++i) {
    int x0, x1, y0, y1;
    cell_range(walls_[i], &x0, &x1, &y0, &y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) cell_walls_[fill[static_cast<size_t>(y) * nx_ + x]++] = static_cast<uint32_t>(i);
  }
}

double World::CastRay(const Point2& o, double angle, double max_range) const {
  if (nx_ == 0) return max_range;
  const double dx = std::cos(angle), dy = std::sin(angle);
  const double max_x = min_x_ + nx_ * cell_m_, max_y = min_y_ + ny_ * cell_m_;
  // Clip the ray [0, max_range] to the grid box (slab test).
  double t0 = 0.0, t1 = max_range;
  auto slab = [&](double origin, double d, double lo, double hi) {
    if (std::abs(d) < 1e-12) return origin >= lo && origin <= hi;
    double ta = (lo - origin) / d, tb = (hi - origin) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    return t0 <= t1;
  };
  if (!slab(o.x, dx, min_x_, max_x) || !slab(o.y, dy, min_y_, max_y)) return max_range;
  const double px = o.x + t0 * dx, py = o.y + t0 * dy;
  int ix = std::clamp(static_cast<int>(std::floor((px - min_x_) / cell_m_)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((py - min_y_) / cell_m_)), 0, ny_ - 1);
  const double inf = std::numeric_limits<double>::infinity();
  const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
  double t_max_x = std::abs(dx) < 1e-12 ? inf : ((min_x_ + (ix + (dx > 0 ? 1 : 0)) * cell_m_) - o.x) / dx;
  double t_max_y = std::abs(dy) < 1e-12 ? inf : ((min_y_ + (iy + (dy > 0 ? 1 : 0)) * cell_m_) - o.y) / dy;
  const double t_delta_x = std::abs(dx) < 1e-12 ? inf : cell_m_ / std::abs(dx);
  const double t_delta_y = std::abs(dy) < 1e-12 ? inf : cell_m_ / std::abs(dy);
  double best = max_range;
  for (;;) {
    const size_t c = static_cast<size_t>(iy) * nx_ + ix;
    for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
      const Segment& s = walls_[cell_walls_[k]];
      const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
      const double denom = dx * ey - dy * ex;
      if (std::abs(denom) < 1e-12) continue;
      const double wx = s.a.x - o.x, wy = s.a.y - o.y;
      const double t = (wx * ey - wy * ex) / denom;
      if (t < 0.0 || t >= best) continue;
      const double u = (wx * dy - wy * dx) / denom;
      if (u < 0.0 || u > 1.0) continue;
      best = t;
    }
    const double t_exit = std::min(t_max_x, t_max_y);
    if (best <= t_exit || t_exit > t1) break;
    if (t_max_x < t_max_y) {
      ix += step_x;
      t_max_x += t_delta_x;
      if (ix < 0 || ix >= nx_) break;
    } else {
      iy += step_y;
      t_max_y += t_delta_y;
      if (iy < 0 || iy >= ny_) break;
    }
  }
  return best;
}

}  // namespace lmd
