// What the localisation pipeline (localizer.h) needs from a collection of
// stored maps: the first-stage search over their place features and each
// map prepared for scan matching. lmdd implements it over its RocksDB store
// and caches (server/), lmd-eval and the tests over maps in memory
// (memory_collection.h).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "core/align/prepared_map.h"
#include "core/place/place_index.h"

namespace lmd {

class MapSource {
 public:
  virtual ~MapSource() = default;

  // PlaceIndex::Search over the collection's maps (with
  // options.anchored_only, over its anchored maps): best first, by votes.
  virtual std::vector<PlaceHypothesis> Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                              const std::function<bool(uint64_t)>& excluded,
                                              PlaceSearchStats* stats) const = 0;

  // The stored map `map_id` prepared for scan matching (PrepareMap with its
  // free space, heading = its place features' compass heading); null if it
  // is no longer stored. Thread-safe.
  virtual std::shared_ptr<const PreparedMap> Prepared(uint64_t map_id) const = 0;
  // The stored map `map_id` prepared at least for the correlative search
  // (PrepareSearchGrid: its points and pyramid), all a coarse fit needs
  // (CorrelativeBound); null if it is no longer stored. A source that
  // prepares maps on demand returns the grid alone when it has nothing
  // more, and completes it in Prepared() (CompletePreparation): most maps
  // fitted are never matched against. Default: Prepared(). Thread-safe.
  virtual std::shared_ptr<const PreparedMap> SearchGrid(uint64_t map_id) const { return Prepared(map_id); }

  // Where a stored map lies on the route of the robot that made it: the
  // robot, and the map's number in the robot's sequence of maps. Maps a few
  // numbers apart on one route overlap and show one place. False when
  // unknown (no robot or sequence given).
  struct Route {
    uint64_t robot = 0;
    uint64_t sequence = 0;
  };
  virtual bool RouteOf(uint64_t map_id, Route* route) const = 0;

  // Maps anchored in the collection's frame (a site map; anchor_index.h).
  struct Anchored {
    uint64_t map_id = 0;
    Pose2 pose;  // the map's own frame in the collection's frame
  };
  // The anchor of `map_id`, if it has one (default: no map is anchored).
  // Thread-safe.
  virtual std::optional<Pose2> AnchorOf(uint64_t /*map_id*/) const { return std::nullopt; }
  // Whether any map is anchored (default: none). Thread-safe.
  virtual bool HasAnchors() const { return false; }
  // AnchorIndex::Near and AnchorIndex::NearestByPath over the anchored maps
  // (default: none), those `excluded` names passed over. Thread-safe.
  virtual std::vector<Anchored> AnchoredNear(const Point2& /*centre*/, double /*radius_m*/, size_t /*per_cell*/,
                                             const std::function<bool(uint64_t)>& /*excluded*/) const {
    return {};
  }
  virtual std::vector<Anchored> NearestAnchored(const std::vector<Point2>& /*path*/, double /*max_gap_m*/,
                                                size_t /*count*/,
                                                const std::function<bool(uint64_t)>& /*excluded*/) const {
    return {};
  }
};

}  // namespace lmd
