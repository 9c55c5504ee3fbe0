// Stored maps anchored in their collection's frame (a site map), found by
// where they lie. Prior queries (prior.h) ask it for the maps near a robot's
// estimated pose instead of searching the whole collection.
//
// A fleet that stores every local map piles up maps of its busy places
// without bound (lmd-bench load --mode fleet: 100 robots add 6,000 maps a
// minute to one building), so no query reads all the maps of a place: each
// grid cell answers with at most a given number of its maps of each kind,
// the newest (highest ids) first, as the newest show the place as it is now.
// The kinds: maps anchored by a given pose (a survey's, a robot's own SLAM
// pose) and maps lmdd anchored itself from a sure fix (derived), which carry
// that fix's error; where both are equally near, the given ones come first.
//
// Thread safety: const methods may run concurrently; Set / Remove need
// exclusive access (the caller's lock).
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/localize/map_source.h"
#include "core/types.h"

namespace lmd {

class AnchorIndex {
 public:
  AnchorIndex() = default;

  // Anchors (or re-anchors) map `id`: `pose` is its own frame in the
  // collection's frame; [min_corner, max_corner] the bounding box of its
  // points in its own frame; `trajectory` (own frame) where its robot drove
  // (none: the map's origin stands for it); `derived`: lmdd found the pose.
  void Set(uint64_t id, const Pose2& pose, const Point2& min_corner, const Point2& max_corner,
           const std::vector<Pose2>& trajectory = {}, bool derived = false);
  // False when `id` is not anchored.
  bool Remove(uint64_t id);

  std::optional<Pose2> Anchor(uint64_t id) const;
  // Anchored maps whose box (in the collection's frame) meets the disk, by
  // id: of each 10 m cell the disk meets, the newest `per_cell` of each kind
  // that `excluded` (optional) does not name.
  std::vector<MapSource::Anchored> Near(const Point2& centre, double radius_m, size_t per_cell,
                                        const std::function<bool(uint64_t)>& excluded = {}) const;
  // The `count` anchored maps whose robots drove nearest `path` (where the
  // query's robot drove, collection frame), none farther than max_gap_m from
  // it: nearest first (the smallest distance between a point of either
  // trajectory, each kept about 1 m apart), but within a metre given anchors
  // before derived ones and then the newer first; those `excluded` names
  // passed over. Searched outwards from the path one 2 m cell at a time,
  // reading the newest `count` of each kind in each cell, until `count` maps
  // are found a cell beyond.
  std::vector<MapSource::Anchored> NearestByPath(const std::vector<Point2>& path, double max_gap_m, size_t count,
                                                 const std::function<bool(uint64_t)>& excluded = {}) const;
  size_t size() const { return maps_.size(); }

 private:
  struct Anchored {
    Pose2 pose;
    Point2 lo, hi;  // bounding box in the collection's frame
    std::vector<Point2> path;
    bool derived = false;
  };
  struct Cell {
    std::vector<uint64_t> ids[2];  // given, derived; ascending
  };
  using Grid = std::unordered_map<uint64_t, Cell>;
  static uint64_t CellKey(int64_t cx, int64_t cy) { return static_cast<uint64_t>(cx) << 32 ^ static_cast<uint32_t>(cy); }
  static int64_t CellOf(double v, double cell_m) { return static_cast<int64_t>(std::floor(v / cell_m)); }
  // The cells of `grid` (cell_m wide) that [lo, hi] meets.
  static std::vector<uint64_t> CellsOf(const Point2& lo, const Point2& hi, double cell_m);
  static void Insert(Grid* grid, uint64_t key, uint64_t id, bool derived);
  static void Erase(Grid* grid, uint64_t key, uint64_t id, bool derived);
  // Calls f(id) for the newest `per_kind` ids of each kind in `cell` that
  // `excluded` does not name.
  template <typename F>
  static void ReadNewest(const Cell& cell, size_t per_kind, const std::function<bool(uint64_t)>& excluded, const F& f);
  std::vector<uint64_t> PathCells(const Anchored& a) const;

  std::unordered_map<uint64_t, Anchored> maps_;
  Grid boxes_;  // 10 m cells -> maps whose box meets them
  Grid paths_;  // 2 m cells -> maps whose trajectory passes through them
};

}  // namespace lmd
