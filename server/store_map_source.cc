#include "server/store_map_source.h"

#include "proto/convert.h"

namespace lmd::server {

std::vector<PlaceHypothesis> StoreMapSource::Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                                    const std::function<bool(uint64_t)>&,
                                                    PlaceSearchStats* stats) const {
  Result<std::vector<PlaceHypothesis>> found = store_->SearchPlaces(collection_, query, options, excluded_, stats);
  return found.ok() ? std::move(found).value() : std::vector<PlaceHypothesis>{};
}

std::shared_ptr<const PreparedMap> StoreMapSource::Prepared(uint64_t map_id) const {
  std::shared_ptr<const PreparedMap> cached = cache_->Find(collection_, map_id);
  if (cached && !cached->SearchGridOnly()) return cached;
  Result<IndexedEntry> entry = store_->Indexed(collection_, map_id);
  if (!entry.ok()) return nullptr;
  Result<v1::StoredMap> stored = store_->GetMap(collection_, entry->map_id);
  if (!stored.ok()) return nullptr;  // deleted meanwhile
  const LocalMap map = MethodView(FromProto(stored->map()));
  const PreparedMapOptions& options = store_->indexing().localize.match.map;
  auto prepared = std::make_shared<const PreparedMap>(
      cached ? CompletePreparation(*cached, map, entry->heading) : PrepareMap(map, options, entry->heading));
  cache_->Put(collection_, map_id, prepared);
  return prepared;
}

std::shared_ptr<const PreparedMap> StoreMapSource::SearchGrid(uint64_t map_id) const {
  if (std::shared_ptr<const PreparedMap> cached = cache_->Find(collection_, map_id)) return cached;
  Result<IndexedEntry> entry = store_->Indexed(collection_, map_id);
  if (!entry.ok()) return nullptr;
  Result<v1::StoredMap> stored = store_->GetMap(collection_, entry->map_id);
  if (!stored.ok()) return nullptr;  // deleted meanwhile
  auto grid = std::make_shared<const PreparedMap>(
      PrepareSearchGrid(MethodView(FromProto(stored->map())).points, store_->indexing().localize.match.map));
  cache_->Put(collection_, map_id, grid);
  return grid;
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
