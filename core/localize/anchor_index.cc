#include "core/localize/anchor_index.h"

#include <algorithm>
#include <unordered_set>

#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

constexpr double kBoxCellM = 10.0;  // grid of the maps' boxes
constexpr double kPathCellM = 2.0;  // grid of the trajectories
constexpr double kPathStepM = 1.0;  // spacing of the kept trajectory points
// Maps whose robots drove within the same metre of the query's path show
// about the same view: among them given anchors rank before derived ones.
constexpr double kGapBandM = 1.0;

double SquaredGap(const std::vector<Point2>& a, const std::vector<Point2>& b) {
  double best = 1e300;
  for (const Point2& p : a) {
    for (const Point2& q : b) best = std::min(best, (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y));
  }
  return best;
}

// `points` thinned to about kPathStepM apart.
std::vector<Point2> Thinned(const std::vector<Point2>& points) {
  std::vector<Point2> kept;
  for (const Point2& p : points) {
    if (kept.empty() || std::hypot(p.x - kept.back().x, p.y - kept.back().y) >= kPathStepM) kept.push_back(p);
  }
  return kept;
}

}  // namespace

std::vector<uint64_t> AnchorIndex::CellsOf(const Point2& lo, const Point2& hi, double cell_m) {
  std::vector<uint64_t> keys;
  for (int64_t cx = CellOf(lo.x, cell_m); cx <= CellOf(hi.x, cell_m); ++cx) {
    for (int64_t cy = CellOf(lo.y, cell_m); cy <= CellOf(hi.y, cell_m); ++cy) keys.push_back(CellKey(cx, cy));
  }
  return keys;
}

void AnchorIndex::Insert(Grid* grid, uint64_t key, uint64_t id, bool derived) {
  std::vector<uint64_t>& ids = (*grid)[key].ids[derived];
  ids.insert(std::upper_bound(ids.begin(), ids.end(), id), id);  // new maps have the highest ids: at the end
}

void AnchorIndex::Erase(Grid* grid, uint64_t key, uint64_t id, bool derived) {
  const auto cell = grid->find(key);
  if (cell == grid->end()) return;
  std::vector<uint64_t>& ids = cell->second.ids[derived];
  const auto it = std::lower_bound(ids.begin(), ids.end(), id);
  if (it != ids.end() && *it == id) ids.erase(it);
  if (cell->second.ids[0].empty() && cell->second.ids[1].empty()) grid->erase(cell);
}

template <typename F>
void AnchorIndex::ReadNewest(const Cell& cell, size_t per_kind, const std::function<bool(uint64_t)>& excluded,
                             const F& f) {
  for (const std::vector<uint64_t>& ids : cell.ids) {
    size_t read = 0;
    for (auto it = ids.rbegin(); it != ids.rend() && read < per_kind; ++it) {
      if (excluded && excluded(*it)) continue;
      ++read;
      f(*it);
    }
  }
}

std::vector<uint64_t> AnchorIndex::PathCells(const Anchored& a) const {
  std::vector<uint64_t> keys;
  for (const Point2& p : a.path) keys.push_back(CellKey(CellOf(p.x, kPathCellM), CellOf(p.y, kPathCellM)));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

void AnchorIndex::Set(uint64_t id, const Pose2& pose, const Point2& min_corner, const Point2& max_corner,
                      const std::vector<Pose2>& trajectory, bool derived) {
  Remove(id);
  Anchored a{pose, {1e300, 1e300}, {-1e300, -1e300}, {}, derived};
  std::vector<Point2> path;
  for (const Pose2& p : trajectory) path.push_back(TransformPoint(pose, {p.x, p.y}));
  a.path = Thinned(path);
  if (a.path.empty()) a.path.push_back({pose.x, pose.y});
  for (const Point2& c : {min_corner, max_corner, Point2{min_corner.x, max_corner.y}, Point2{max_corner.x, min_corner.y}}) {
    const Point2 p = TransformPoint(pose, c);
    a.lo = {std::min(a.lo.x, p.x), std::min(a.lo.y, p.y)};
    a.hi = {std::max(a.hi.x, p.x), std::max(a.hi.y, p.y)};
  }
  for (uint64_t key : CellsOf(a.lo, a.hi, kBoxCellM)) Insert(&boxes_, key, id, derived);
  for (uint64_t key : PathCells(a)) Insert(&paths_, key, id, derived);
  maps_[id] = std::move(a);
}

bool AnchorIndex::Remove(uint64_t id) {
  const auto it = maps_.find(id);
  if (it == maps_.end()) return false;
  const bool derived = it->second.derived;
  for (uint64_t key : CellsOf(it->second.lo, it->second.hi, kBoxCellM)) Erase(&boxes_, key, id, derived);
  for (uint64_t key : PathCells(it->second)) Erase(&paths_, key, id, derived);
  maps_.erase(it);
  return true;
}

std::optional<Pose2> AnchorIndex::Anchor(uint64_t id) const {
  const auto it = maps_.find(id);
  if (it == maps_.end()) return std::nullopt;
  return it->second.pose;
}

std::vector<MapSource::Anchored> AnchorIndex::Near(const Point2& centre, double radius_m, size_t per_cell,
                                                   const std::function<bool(uint64_t)>& excluded) const {
  std::vector<uint64_t> ids;
  const double r = std::max(0.0, radius_m);
  for (uint64_t key : CellsOf({centre.x - r, centre.y - r}, {centre.x + r, centre.y + r}, kBoxCellM)) {
    const auto cell = boxes_.find(key);
    if (cell == boxes_.end()) continue;
    ReadNewest(cell->second, per_cell, excluded, [&](uint64_t id) {
      const Anchored& a = maps_.at(id);
      const double dx = std::max({a.lo.x - centre.x, 0.0, centre.x - a.hi.x});
      const double dy = std::max({a.lo.y - centre.y, 0.0, centre.y - a.hi.y});
      if (dx * dx + dy * dy <= r * r) ids.push_back(id);
    });
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<MapSource::Anchored> out;
  for (uint64_t id : ids) out.push_back({id, maps_.at(id).pose});
  return out;
}

std::vector<MapSource::Anchored> AnchorIndex::NearestByPath(const std::vector<Point2>& driven, double max_gap_m,
                                                            size_t count, const std::function<bool(uint64_t)>& excluded) const {
  const std::vector<Point2> path = Thinned(driven);
  if (path.empty() || count == 0 || !(max_gap_m >= 0)) return {};
  std::vector<std::pair<int64_t, int64_t>> origins;
  for (const Point2& p : path) origins.push_back({CellOf(p.x, kPathCellM), CellOf(p.y, kPathCellM)});
  std::sort(origins.begin(), origins.end());
  origins.erase(std::unique(origins.begin(), origins.end()), origins.end());
  std::unordered_set<uint64_t> visited;
  std::unordered_map<uint64_t, double> gaps;  // id -> squared gap
  auto read = [&](int64_t cx, int64_t cy) {
    if (!visited.insert(CellKey(cx, cy)).second) return;
    const auto cell = paths_.find(CellKey(cx, cy));
    if (cell == paths_.end()) return;
    ReadNewest(cell->second, count, excluded, [&](uint64_t id) {
      if (gaps.count(id) == 0) gaps[id] = SquaredGap(path, maps_.at(id).path);
    });
  };
  // Ring d: the cells d cells (Chebyshev) from a cell of the path. A map
  // first met in ring d is at least (d - 1) cells from the path, so one ring
  // past the one that completes `count` finds every map nearer than those.
  const int64_t last_ring = static_cast<int64_t>(std::ceil(max_gap_m / kPathCellM)) + 1;
  int64_t stop_after = last_ring;
  for (int64_t d = 0; d <= stop_after; ++d) {
    for (const auto& [ox, oy] : origins) {
      for (int64_t i = -d; i <= d; ++i) {
        read(ox + i, oy - d), read(ox + i, oy + d);
        if (i != -d && i != d) read(ox - d, oy + i), read(ox + d, oy + i);
      }
    }
    if (gaps.size() >= count && stop_after == last_ring) stop_after = std::min(last_ring, d + 1);
  }
  struct Ranked {
    double band;  // whole metres of gap
    bool derived;
    double gap;
    uint64_t id;
  };
  std::vector<Ranked> order;
  for (const auto& [id, squared] : gaps) {
    const double gap = std::sqrt(squared);
    if (gap <= max_gap_m) order.push_back({std::floor(gap / kGapBandM), maps_.at(id).derived, gap, id});
  }
  std::sort(order.begin(), order.end(), [](const Ranked& a, const Ranked& b) {
    if (a.band != b.band) return a.band < b.band;
    if (a.derived != b.derived) return !a.derived;
    return a.gap != b.gap ? a.gap < b.gap : a.id > b.id;
  });
  if (order.size() > count) order.resize(count);
  std::vector<MapSource::Anchored> out;
  for (const Ranked& r : order) out.push_back({r.id, maps_.at(r.id).pose});
  return out;
}

}  // namespace lmd
