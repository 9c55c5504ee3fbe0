// A collection of stored maps held in memory, for lmd-eval, benchmarks and
// tests: the same MapSource lmdd serves from its store, without RocksDB.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/localize/anchor_index.h"
#include "core/localize/localizer.h"
#include "core/localize/map_source.h"
#include "core/place/place_index.h"
#include "core/status.h"

namespace lmd {

class MemoryCollection : public MapSource {
 public:
  // Stores a map under `id` (PreparePlace's result), with its place on its
  // robot's route if known (MapSource::Route) and its trajectory (own frame;
  // where it is anchored, prior queries prefer maps whose robot drove where
  // the query's did). AlreadyExists or PlaceIndex::Add's errors; nothing
  // changes on error. Not thread-safe.
  Status Add(uint64_t id, PreparedPlace place, std::optional<Route> route = std::nullopt,
             std::vector<Pose2> trajectory = {});

  std::vector<PlaceHypothesis> Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                      const std::function<bool(uint64_t)>& excluded,
                                      PlaceSearchStats* stats) const override;
  std::shared_ptr<const PreparedMap> Prepared(uint64_t map_id) const override;
  bool RouteOf(uint64_t map_id, Route* route) const override;
  std::optional<Pose2> AnchorOf(uint64_t map_id) const override;
  bool HasAnchors() const override { return anchors_.size() > 0; }
  std::vector<Anchored> AnchoredNear(const Point2& centre, double radius_m, size_t per_cell,
                                     const std::function<bool(uint64_t)>& excluded) const override;
  std::vector<Anchored> NearestAnchored(const std::vector<Point2>& path, double max_gap_m, size_t count,
                                        const std::function<bool(uint64_t)>& excluded) const override;

  // Anchors a stored map in the collection's frame; false if not stored.
  bool SetAnchor(uint64_t id, const Pose2& pose);

  const PlaceIndex& index() const { return index_; }
  size_t size() const { return maps_.size(); }

 private:
  PlaceIndex index_;
  AnchorIndex anchors_;
  struct Stored {
    std::shared_ptr<const PreparedMap> map;
    std::optional<Route> route;
    std::vector<Pose2> trajectory;
  };
  std::unordered_map<uint64_t, Stored> maps_;
};

}  // namespace lmd
