// The default method's view of one collection of lmdd's store (MapSource,
// core/localize/map_source.h): the store's place index, maps prepared for
// scan matching (or gridded for a coarse fit alone) from the cache or, on a
// miss, from the stored map, and
// routes from the maps' metadata. Ids are the store's index ids. One per
// query: it carries the request's excluded map ids.
#pragma once

#include <optional>
#include <string>
#include <unordered_set>

#include "core/localize/map_source.h"
#include "core/localize/prepared_map_cache.h"
#include "server/indexing.h"
#include "server/map_store.h"

namespace lmd::server {

class StoreMapSource : public MapSource {
 public:
  // `store` and `cache` must outlive the source. Maps whose id is in
  // `excluded` are never returned by Search or the anchored queries (the
  // core's own predicate, which works on index ids, is not used).
  StoreMapSource(const MapStore* store, PreparedMapCache* cache, std::string collection,
                 std::unordered_set<std::string> excluded)
      : store_(store), cache_(cache), collection_(std::move(collection)), excluded_(std::move(excluded)) {}

  std::vector<PlaceHypothesis> Search(const PlaceFeatures& query, const PlaceSearchOptions& options,
                                      const std::function<bool(uint64_t)>& excluded,
                                      PlaceSearchStats* stats) const override;
  std::shared_ptr<const PreparedMap> Prepared(uint64_t map_id) const override;
  std::shared_ptr<const PreparedMap> SearchGrid(uint64_t map_id) const override;
  bool RouteOf(uint64_t map_id, Route* route) const override;
  std::optional<Pose2> AnchorOf(uint64_t map_id) const override;
  bool HasAnchors() const override;
  std::vector<Anchored> AnchoredNear(const Point2& centre, double radius_m, size_t per_cell,
                                     const std::function<bool(uint64_t)>& excluded) const override;
  std::vector<Anchored> NearestAnchored(const std::vector<Point2>& path, double max_gap_m, size_t count,
                                        const std::function<bool(uint64_t)>& excluded) const override;

 private:
  // The stored map and its heading, for the cache's misses.
  std::optional<PreparedMapCache::Source> Read(uint64_t map_id) const;

  const MapStore* const store_;
  PreparedMapCache* const cache_;
  const std::string collection_;
  const std::unordered_set<std::string> excluded_;
};

}  // namespace lmd::server
