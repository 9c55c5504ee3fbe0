#include "server/store_map_source.h"

#include "proto/convert.h"

namespace lmd::server {

std::vector<PlaceHypothesis> StoreMapSource::Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                                    const std::function<bool(uint64_t)>&,
                                                    PlaceSearchStats* stats) const {
  Result<std::vector<PlaceHypothesis>> found = store_->SearchPlaces(collection_, query, options, excluded_, stats);
  return found.ok() ? std::move(found).value() : std::vector<PlaceHypothesis>{};
}

std::optional<PreparedMapCache::Source> StoreMapSource::Read(uint64_t map_id) const {
  Result<IndexedEntry> entry = store_->Indexed(collection_, map_id);
  if (!entry.ok()) return std::nullopt;
  Result<v1::StoredMap> stored = store_->GetMap(collection_, entry->map_id);
  if (!stored.ok()) return std::nullopt;  // deleted meanwhile
  return PreparedMapCache::Source{MethodView(FromProto(stored->map())), entry->heading};
}

std::shared_ptr<const PreparedMap> StoreMapSource::Prepared(uint64_t map_id) const {
  return cache_->Prepared(collection_, map_id, store_->indexing().localize.match.map, [&] { return Read(map_id); });
}

std::shared_ptr<const PreparedMap> StoreMapSource::SearchGrid(uint64_t map_id) const {
  return cache_->SearchGrid(collection_, map_id, store_->indexing().localize.match.map, [&] { return Read(map_id); });
}

bool StoreMapSource::RouteOf(uint64_t map_id, Route* route) const {
  return store_->RouteOf(collection_, map_id, route);
}

std::optional<Pose2> StoreMapSource::AnchorOf(uint64_t map_id) const { return store_->AnchorOf(collection_, map_id); }

bool StoreMapSource::HasAnchors() const { return store_->HasAnchors(collection_); }

std::vector<MapSource::Anchored> StoreMapSource::AnchoredNear(const Point2& centre, double radius_m, size_t per_cell,
                                                              const std::function<bool(uint64_t)>&) const {
  return store_->AnchoredNear(collection_, centre, radius_m, per_cell, excluded_);
}

std::vector<MapSource::Anchored> StoreMapSource::NearestAnchored(const std::vector<Point2>& path, double max_gap_m,
                                                                 size_t count,
                                                                 const std::function<bool(uint64_t)>&) const {
  return store_->NearestAnchored(collection_, path, max_gap_m, count, excluded_);
}

}  // namespace lmd::server
