#include "core/localize/memory_collection.h"

namespace lmd {

Status MemoryCollection::Add(uint64_t id, PreparedPlace place, std::optional<Route> route,
                             std::vector<Pose2> trajectory) {
  if (maps_.count(id) != 0) return Status::AlreadyExists("map " + std::to_string(id) + " is already stored");
  Status added = index_.Add(id, std::move(place.features));
  if (!added.ok()) return added;
  maps_[id] = {std::move(place.map), route, std::move(trajectory)};
  return Status::Ok();
}

std::vector<PlaceHypothesis> MemoryCollection::Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                                      const std::function<bool(uint64_t)>& excluded,
                                                      PlaceSearchStats* stats) const {
  if (!options.anchored_only) return index_.Search(query, options, excluded, stats);
  return index_.Search(query, options, [&](uint64_t id) { return (excluded && excluded(id)) || !anchors_.Anchor(id); },
                       stats);
}

std::shared_ptr<const PreparedMap> MemoryCollection::Prepared(uint64_t map_id) const {
  const auto it = maps_.find(map_id);
  return it == maps_.end() ? nullptr : it->second.map;
}

bool MemoryCollection::RouteOf(uint64_t map_id, Route* route) const {
  const auto it = maps_.find(map_id);
  if (it == maps_.end() || !it->second.route) return false;
  *route = *it->second.route;
  return true;
}

std::optional<Pose2> MemoryCollection::AnchorOf(uint64_t map_id) const { return anchors_.Anchor(map_id); }

std::vector<MapSource::Anchored> MemoryCollection::AnchoredNear(const Point2& centre, double radius_m, size_t per_cell,
                                                                const std::function<bool(uint64_t)>& excluded) const {
  return anchors_.Near(centre, radius_m, per_cell, excluded);
}

std::vector<MapSource::Anchored> MemoryCollection::NearestAnchored(const std::vector<Point2>& path, double max_gap_m,
                                                                   size_t count,
                                                                   const std::function<bool(uint64_t)>& excluded) const {
  return anchors_.NearestByPath(path, max_gap_m, count, excluded);
}

bool MemoryCollection::SetAnchor(uint64_t id, const Pose2& pose) {
  const auto it = maps_.find(id);
  if (it == maps_.end()) return false;
  anchors_.Set(id, pose, it->second.map->min_corner, it->second.map->max_corner, it->second.trajectory);
  return true;
}

}  // namespace lmd
