// Stored maps anchored in their collection's frame (a site map), found by
// where they lie: a grid of cells, each listing the maps whose anchored
// bounding box meets it. Prior queries (prior.h) ask it for the maps near a
// robot's estimated pose instead of searching the whole collection.
//
// Thread safety: const methods may run concurrently; Set / Remove need
// exclusive access (the caller's lock).
#pragma once

#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/localize/map_source.h"
#include "core/types.h"

namespace lmd {

class AnchorIndex {
 public:
  // `cell_m`: grid cell (m); a map is listed in every cell its box meets.
  explicit AnchorIndex(double cell_m = 10.0);

  // Anchors (or re-anchors) map `id`: `pose` is its own frame in the
  // collection's frame; [min_corner, max_corner] the bounding box of its
  // points in its own frame; `trajectory` (own frame) where its robot drove.
  void Set(uint64_t id, const Pose2& pose, const Point2& min_corner, const Point2& max_corner,
           const std::vector<Pose2>& trajectory = {});
  // False when `id` is not anchored.
  bool Remove(uint64_t id);

  std::optional<Pose2> Anchor(uint64_t id) const;
  // Anchored maps whose box (in the collection's frame) meets the disk, by id.
  std::vector<MapSource::Anchored> Near(const Point2& centre, double radius_m) const;
  size_t size() const { return maps_.size(); }

 private:
  struct Anchored {
    Pose2 pose;
    Point2 lo, hi;  // bounding box in the collection's frame
    std::vector<Point2> path;
  };
  static uint64_t CellKey(int64_t cx, int64_t cy) { return static_cast<uint64_t>(cx) << 32 ^ static_cast<uint32_t>(cy); }
  template <typename F>
  void ForCells(const Point2& lo, const Point2& hi, const F& f) const;

  double cell_m_;
  std::unordered_map<uint64_t, Anchored> maps_;
  std::unordered_map<uint64_t, std::vector<uint64_t>> cells_;
};

}  // namespace lmd
