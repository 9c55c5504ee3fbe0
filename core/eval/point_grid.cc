#include "core/eval/point_grid.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/localmap/cell_set.h"

namespace lmd {

PointGrid::PointGrid(const std::vector<Point2>& points, double cell_m) : cell_(cell_m) {
  const size_t n = points.size();
  if (n == 0) return;
  ox_ = std::floor(points[0].x);
  oy_ = std::floor(points[0].y);
  std::vector<uint64_t> key(n);
  for (size_t i = 0; i < n; ++i) key[i] = CellKeyOf(points[i].x, points[i].y, cell_);
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key[a] < key[b]; });
  xs_.resize(n);
  ys_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    xs_[i] = static_cast<float>(points[order[i]].x - ox_);
    ys_[i] = static_cast<float>(points[order[i]].y - oy_);
  }
  size_t cells = 0;
  for (size_t i = 0; i < n; ++i) cells += (i == 0 || key[order[i]] != key[order[i - 1]]) ? 1 : 0;
  size_t cap = 16;
  while (cap < cells * 2) cap <<= 1;
  keys_.assign(cap, ~0ULL);
  begin_.assign(cap, 0);
  end_.assign(cap, 0);
  const size_t mask = cap - 1;
  for (size_t i = 0; i < n;) {
    const uint64_t k = key[order[i]];
    size_t j = i;
    while (j < n && key[order[j]] == k) ++j;
    size_t slot = MixKey(k) & mask;
    while (keys_[slot] != ~0ULL) slot = (slot + 1) & mask;
    keys_[slot] = k;
    begin_[slot] = static_cast<uint32_t>(i);
    end_[slot] = static_cast<uint32_t>(j);
    i = j;
  }
}

void PointGrid::Cell(int64_t ix, int64_t iy, uint32_t* begin, uint32_t* end) const {
  const uint64_t k = CellKey(ix, iy);
  const size_t mask = keys_.size() - 1;
  size_t slot = MixKey(k) & mask;
  while (keys_[slot] != ~0ULL) {
    if (keys_[slot] == k) {
      *begin = begin_[slot];
      *end = end_[slot];
      return;
    }
    slot = (slot + 1) & mask;
  }
  *begin = *end = 0;
}

double PointGrid::NearestDistance(const Point2& p, double limit) const {
  if (xs_.empty()) return limit;
  const int64_t cx = static_cast<int64_t>(std::floor(p.x / cell_));
  const int64_t cy = static_cast<int64_t>(std::floor(p.y / cell_));
  const float px = static_cast<float>(p.x - ox_), py = static_cast<float>(p.y - oy_);
  double best2 = limit * limit;
  const int64_t max_ring = static_cast<int64_t>(std::ceil(limit / cell_)) + 1;
  for (int64_t ring = 0; ring <= max_ring; ++ring) {
    // Every point in this ring or beyond is at least (ring - 1) * cell away.
    const double lower = (ring - 1) * cell_;
    if (ring > 0 && lower > 0 && lower * lower >= best2) break;
    for (int64_t dy = -ring; dy <= ring; ++dy) {
      const bool edge_row = dy == -ring || dy == ring;
      for (int64_t dx = -ring; dx <= ring; dx += edge_row ? 1 : 2 * ring) {
        uint32_t b, e;
        Cell(cx + dx, cy + dy, &b, &e);
        for (uint32_t i = b; i < e; ++i) {
          const float ex = xs_[i] - px, ey = ys_[i] - py;
          const double d2 = static_cast<double>(ex) * ex + static_cast<double>(ey) * ey;
          if (d2 < best2) best2 = d2;
        }
        if (ring == 0) break;
      }
    }
  }
  return std::sqrt(best2);
}

void PointGrid::GatherBlock(int64_t cx, int64_t cy, std::vector<Point2>* out) const {
  if (xs_.empty()) return;
  for (int64_t dy = -1; dy <= 1; ++dy) {
    for (int64_t dx = -1; dx <= 1; ++dx) {
      uint32_t b, e;
      Cell(cx + dx, cy + dy, &b, &e);
      for (uint32_t i = b; i < e; ++i) out->push_back({xs_[i] + ox_, ys_[i] + oy_});
    }
  }
}

bool PointGrid::AnyWithin(const Point2& p, double radius) const {
  if (xs_.empty()) return false;
  const int64_t cx = static_cast<int64_t>(std::floor(p.x / cell_));
  const int64_t cy = static_cast<int64_t>(std::floor(p.y / cell_));
  const double r2 = radius * radius;
  for (int64_t dy = -1; dy <= 1; ++dy) {
    for (int64_t dx = -1; dx <= 1; ++dx) {
      uint32_t b, e;
      Cell(cx + dx, cy + dy, &b, &e);
      for (uint32_t i = b; i < e; ++i) {
        const double ex = xs_[i] - (p.x - ox_), ey = ys_[i] - (p.y - oy_);
        if (ex * ex + ey * ey <= r2) return true;
      }
    }
  }
  return false;
}

}  // namespace lmd
