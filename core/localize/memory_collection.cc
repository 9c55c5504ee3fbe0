#include "core/localize/memory_collection.h"

namespace lmd {

Status MemoryCollection::Add(uint64_t id, PreparedPlace place, std::optional<Route> route) {
  if (maps_.count(id) != 0) return Status::AlreadyExists("map " + std::to_string(id) + " is already stored");
  Status added = index_.Add(id, std::move(place.features));
  if (!added.ok()) return added;
  maps_[id] = {std::move(place.map), route};
  return Status::Ok();
}

std::vector<PlaceHypothesis> MemoryCollection::Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                                      const std::function<bool(uint64_t)>& excluded,
                                                      PlaceSearchStats* stats) const {
  return index_.Search(query, options, excluded, stats);
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

}  // namespace lmd
