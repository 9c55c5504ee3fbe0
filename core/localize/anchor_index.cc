#include "core/localize/anchor_index.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

constexpr double kPathStepM = 1.0;  // spacing of the kept trajectory points

}  // namespace

AnchorIndex::AnchorIndex(double cell_m) : cell_m_(cell_m > 0 ? cell_m : 10.0) {}

template <typename F>
void AnchorIndex::ForCells(const Point2& lo, const Point2& hi, const F& f) const {
  const int64_t x0 = static_cast<int64_t>(std::floor(lo.x / cell_m_)), x1 = static_cast<int64_t>(std::floor(hi.x / cell_m_));
  const int64_t y0 = static_cast<int64_t>(std::floor(lo.y / cell_m_)), y1 = static_cast<int64_t>(std::floor(hi.y / cell_m_));
  for (int64_t cx = x0; cx <= x1; ++cx) {
    for (int64_t cy = y0; cy <= y1; ++cy) f(CellKey(cx, cy));
  }
}

void AnchorIndex::Set(uint64_t id, const Pose2& pose, const Point2& min_corner, const Point2& max_corner,
                      const std::vector<Pose2>& trajectory) {
  Remove(id);
  Anchored a{pose, {1e300, 1e300}, {-1e300, -1e300}, {}};
  for (const Pose2& p : trajectory) {
    const Point2 at = TransformPoint(pose, {p.x, p.y});
    if (a.path.empty() || std::hypot(at.x - a.path.back().x, at.y - a.path.back().y) >= kPathStepM) a.path.push_back(at);
  }
  for (const Point2& c : {min_corner, max_corner, Point2{min_corner.x, max_corner.y}, Point2{max_corner.x, min_corner.y}}) {
    const Point2 p = TransformPoint(pose, c);
    a.lo = {std::min(a.lo.x, p.x), std::min(a.lo.y, p.y)};
    a.hi = {std::max(a.hi.x, p.x), std::max(a.hi.y, p.y)};
  }
  ForCells(a.lo, a.hi, [&](uint64_t key) { cells_[key].push_back(id); });
  maps_[id] = a;
}

bool AnchorIndex::Remove(uint64_t id) {
  const auto it = maps_.find(id);
  if (it == maps_.end()) return false;
  ForCells(it->second.lo, it->second.hi, [&](uint64_t key) {
    std::vector<uint64_t>& ids = cells_[key];
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());
    if (ids.empty()) cells_.erase(key);
  });
  maps_.erase(it);
  return true;
}

std::optional<Pose2> AnchorIndex::Anchor(uint64_t id) const {
  const auto it = maps_.find(id);
  if (it == maps_.end()) return std::nullopt;
  return it->second.pose;
}

std::vector<MapSource::Anchored> AnchorIndex::Near(const Point2& centre, double radius_m) const {
  std::vector<uint64_t> ids;
  const double r = std::max(0.0, radius_m);
  ForCells({centre.x - r, centre.y - r}, {centre.x + r, centre.y + r}, [&](uint64_t key) {
    const auto it = cells_.find(key);
    if (it == cells_.end()) return;
    for (uint64_t id : it->second) {
      const Anchored& a = maps_.at(id);
      const double dx = std::max({a.lo.x - centre.x, 0.0, centre.x - a.hi.x});
      const double dy = std::max({a.lo.y - centre.y, 0.0, centre.y - a.hi.y});
      if (dx * dx + dy * dy <= r * r) ids.push_back(id);
    }
  });
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<MapSource::Anchored> out;
  for (uint64_t id : ids) {
    const Anchored& a = maps_.at(id);
    out.push_back({id, a.pose, a.lo, a.hi, a.path});
  }
  return out;
}

}  // namespace lmd
