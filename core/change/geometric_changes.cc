#include "core/change/geometric_changes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "core/change/sightings.h"

namespace lmd {
namespace {

size_t Root(std::vector<size_t>& parent, size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

uint64_t CellKey(int64_t x, int64_t y) { return (static_cast<uint64_t>(x) << 32) ^ static_cast<uint32_t>(y); }

// Groups of points linked by distances below radius (single linkage), via a
// grid of radius-sized cells: only the 3x3 neighbouring cells are compared.
std::vector<std::vector<size_t>> LinkedGroups(const std::vector<Point2>& points, double radius) {
  std::vector<size_t> parent(points.size());
  std::iota(parent.begin(), parent.end(), 0);
  const double cell = std::max(radius, 1e-3), r2 = radius * radius;
  std::unordered_map<uint64_t, std::vector<size_t>> cells;
  auto cell_of = [&](const Point2& p, int64_t* x, int64_t* y) {
    *x = static_cast<int64_t>(std::floor(p.x / cell));
    *y = static_cast<int64_t>(std::floor(p.y / cell));
  };
  for (size_t i = 0; i < points.size(); ++i) {
    int64_t x, y;
    cell_of(points[i], &x, &y);
    cells[CellKey(x, y)].push_back(i);
  }
  for (size_t i = 0; i < points.size(); ++i) {
    int64_t x, y;
    cell_of(points[i], &x, &y);
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const auto it = cells.find(CellKey(x + dx, y + dy));
        if (it == cells.end()) continue;
        for (size_t j : it->second) {
          const double ex = points[i].x - points[j].x, ey = points[i].y - points[j].y;
          if (j > i && ex * ex + ey * ey <= r2) parent[Root(parent, i)] = Root(parent, j);
        }
      }
    }
  }
  std::unordered_map<size_t, size_t> group_of_root;
  std::vector<std::vector<size_t>> groups;
  for (size_t i = 0; i < points.size(); ++i) {
    const auto [it, added] = group_of_root.emplace(Root(parent, i), groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(i);
  }
  return groups;
}

// True when every cell of `map`'s free grid within `margin` of p (a square of
// cells, at most 10 cells each way) is free.
bool DeepInFreeSpace(const PreparedMap& map, const Point2& p, double margin) {
  const double step = map.occupancy.cell_m();
  const double cells = margin / step;
  const int reach = cells > 0 ? static_cast<int>(std::lround(std::min(cells, 10.0))) : 0;  // NaN: 0
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      if (!InFreeSpace(map, {p.x + dx * step, p.y + dy * step})) return false;
    }
  }
  return true;
}

// Distance from p to the nearest finite pose of `trajectory`; 0 if it has none.
double RangeOf(const Point2& p, const std::vector<Pose2>& trajectory) {
  double best2 = std::numeric_limits<double>::infinity();
  for (const Pose2& t : trajectory) {
    const double d2 = (t.x - p.x) * (t.x - p.x) + (t.y - p.y) * (t.y - p.y);
    if (d2 < best2) best2 = d2;  // false for NaN
  }
  return std::isfinite(best2) ? std::sqrt(best2) : 0.0;
}

// Removes the change points (with their evidence and free votes, n per
// point) that the query's own scans saw through more than `share` of the
// times they saw them at all: things that moved while the robot mapped.
void DropSeenThrough(const std::vector<Sightings>& sightings, double share, size_t n, std::vector<Point2>* changed,
                     std::vector<double>* evidence, std::vector<uint8_t>* seen_free) {
  size_t kept = 0;
  for (size_t i = 0; i < changed->size(); ++i) {
    const double seen = sightings[i].returns + sightings[i].through;
    if (seen > 0 && sightings[i].through > share * seen) continue;
    (*changed)[kept] = (*changed)[i];
    (*evidence)[kept] = (*evidence)[i];
    std::copy_n(seen_free->begin() + i * n, n, seen_free->begin() + kept * n);
    ++kept;
  }
  changed->resize(kept), evidence->resize(kept), seen_free->resize(kept * n);
}

}  // namespace

std::vector<ChangeMask> GeometricChanges(const std::vector<Point2>& query_points,
                                         const std::vector<Pose2>& query_trajectory,
                                         const std::vector<Scan>& query_scans,
                                         const std::vector<AlignedMap>& maps,
                                         const GeometricChangeOptions& options) {
  struct Placed {
    const AlignedMap* map;
    double c, s;
  };
  std::vector<Placed> placed;
  for (const AlignedMap& m : maps) {
    if (m.db && !m.db->empty()) placed.push_back({&m, std::cos(m.pose.theta), std::sin(m.pose.theta)});
  }
  // Change points, and for each the maps that saw it free: seen_free[i * n + k]
  // for change point i and placed map k.
  const size_t n = placed.size();
  std::vector<Point2> changed;
  std::vector<double> evidence;  // per change point, its weight in the ranking
  std::vector<uint8_t> seen_free;
  std::vector<uint8_t> free(n);
  std::vector<Point2> in_db(n);
  for (const Point2& p : query_points) {
    bool explained = false, any_free = false;
    for (size_t k = 0; k < n && !explained; ++k) {
      const Pose2& t = placed[k].map->pose;
      in_db[k] = {t.x + placed[k].c * p.x - placed[k].s * p.y, t.y + placed[k].s * p.x + placed[k].c * p.y};
      explained = NearestPoint(*placed[k].map->db, in_db[k], options.explained_radius_m) >= 0;
      free[k] = !explained && InFreeSpace(*placed[k].map->db, in_db[k]);
      any_free = any_free || free[k];
    }
    if (explained || !any_free) continue;
    changed.push_back(p);
    seen_free.insert(seen_free.end(), free.begin(), free.end());
    double weight = 1.0;
    if (options.rank_by_evidence) {
      bool deep = false;
      for (size_t k = 0; k < n && !deep; ++k) {
        deep = free[k] && DeepInFreeSpace(*placed[k].map->db, in_db[k], options.free_margin_m);
      }
      weight = deep ? 1.0 : options.edge_weight;
      if (!query_trajectory.empty() && options.range_scale_m > 0) {
        weight /= 1.0 + RangeOf(p, query_trajectory) / options.range_scale_m;
      }
    }
    evidence.push_back(weight);
  }
  if (options.seen_through_share < 1.0 && !query_scans.empty()) {
    DropSeenThrough(CountSightings(changed, query_scans), options.seen_through_share, n, &changed, &evidence,
                    &seen_free);
  }
  // The evidence a mask needs, given the change points outside it.
  auto floor = [&](size_t points_in_mask) {
    if (options.floor_doubling_share <= 0 || query_points.empty()) return options.min_evidence;
    const double elsewhere = static_cast<double>(changed.size() - points_in_mask) / query_points.size();
    return options.min_evidence * (1.0 + elsewhere / options.floor_doubling_share);
  };
  std::vector<ChangeMask> masks;
  for (const std::vector<size_t>& group : LinkedGroups(changed, options.merge_radius_m)) {
    if (group.size() < std::max<size_t>(1, options.min_points)) continue;
    ChangeMask mask;
    std::vector<size_t> free_votes(n, 0);
    double score = 0;
    for (size_t i : group) {
      score += evidence[i];
      mask.points.push_back(changed[i]);
      mask.scores.push_back(1.0);
      mask.centre.x += changed[i].x / group.size();
      mask.centre.y += changed[i].y / group.size();
      for (size_t k = 0; k < n; ++k) free_votes[k] += seen_free[i * n + k];
    }
    const size_t credited = std::max_element(free_votes.begin(), free_votes.end()) - free_votes.begin();
    mask.db_map_id = placed[credited].map->id;
    mask.score = score;
    if (score < floor(group.size())) continue;
    masks.push_back(std::move(mask));
  }
  std::stable_sort(masks.begin(), masks.end(), [](const ChangeMask& a, const ChangeMask& b) {
    return a.score != b.score ? a.score > b.score : a.points.size() > b.points.size();
  });
  for (size_t r = 0; r < masks.size(); ++r) masks[r].rank = r;
  return masks;
}

}  // namespace lmd
