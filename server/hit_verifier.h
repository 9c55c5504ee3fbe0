// HitVerifier: the product default method's second stage. The index's best
// candidates are verified geometrically (core/align/verify_hits.h: the query's
// points aligned onto each candidate's points by our scan matcher) and
// re-ranked by aligned overlap; each verified hit gets the scan matcher's
// metric pose. Prepared db maps (likelihood pyramids, ~100-200 KB each, 1-5 ms
// to build) are kept in an LRU cache of bounded bytes keyed by the map's index id, which
// changes whenever a map is replaced, so a cached entry is never stale.
// A query's own prepared map (for reverse conflicts) is kept too, keyed by
// its content: a robot's newest map is usually queried and then stored (or
// stored, then queried), and becomes a hit of later queries; that first
// preparation is then reused instead of built again.
#pragma once

#include <atomic>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/align/verify_hits.h"
#include "core/status.h"
#include "server/descriptor_cache.h"
#include "server/map_store.h"

namespace lmd::server {

struct VerifiedStoreHit {
  StoreHit hit;             // the index's hit (its rank is the retrieval rank)
  bool verified = false;
  double score = 0.0;       // verification score (verify_hits.h); the index's K if not verified
  Pose2 pose;               // scan-matched pose of the query in the db map's frame (verified only)
  std::shared_ptr<const PreparedMap> prepared;  // the db map as matched (verified only)
};

class HitVerifier {
 public:
  // `store` must outlive the verifier; prepared maps are kept up to
  // `cache_bytes` (PreparedMap::MemoryBytes).
  HitVerifier(const MapStore* store, size_t cache_bytes) : store_(store), capacity_bytes_(cache_bytes) {}

  // Verifies the first `candidates` hits of `hits` (all of them if fewer)
  // against `query`, in retrieval order, stopping once `enough_matches` of
  // them matched well (0: never stop; VerifyOptions::enough_matches), with
  // reverse conflicts weighted by `reverse_conflict_weight` (0: not measured), and
  // returns every hit re-ranked: verified ones by verification score, the
  // rest after them in retrieval order. `query_lmd` supplies the planned
  // frame for the index's pose guesses; `query_key` is the query's content
  // key (DescriptorCache::KeyOf of its wire bytes). Once `cancelled`
  // returns true, no further hit is matched and the result is Cancelled.
  Result<std::vector<VerifiedStoreHit>> Verify(const std::string& collection, const LocalMap& query,
                                               const DescriptorCache::Key& query_key, const Lmd& query_lmd,
                                               const std::vector<StoreHit>& hits,
                                               size_t candidates, size_t enough_matches,
                                               double reverse_conflict_weight,
                                               const std::function<bool()>& cancelled);

  // How many maps this verifier has prepared (PrepareMap calls), queries included.
  size_t maps_prepared() const { return maps_prepared_; }
  // Bytes the cache holds now.
  size_t cached_bytes() const;

 private:
  // The prepared db map of a hit, from the cache (by index id, or by content
  // if it was prepared as a query) or built from the store; `heading` is its
  // planned frame's heading (the same entropy compass).
  Result<std::shared_ptr<const PreparedMap>> Prepared(const std::string& collection, const StoreHit& hit,
                                                      double heading);
  std::shared_ptr<const PreparedMap> Prepare(const LocalMap& map, double heading);

  // The cache, under mutex_: Find moves an entry to the front, Take removes
  // it, Put adds one (if it fits and is new) and evicts the least recent.
  std::shared_ptr<const PreparedMap> Find(const std::string& key);
  std::shared_ptr<const PreparedMap> Take(const std::string& key);
  void Put(const std::string& key, std::shared_ptr<const PreparedMap> prepared);

  const MapStore* const store_;
  const size_t capacity_bytes_;
  std::atomic<size_t> maps_prepared_{0};
  std::atomic<bool> query_maps_kept_{false};  // a query's prepared map was ever cached
  mutable std::mutex mutex_;
  size_t cached_bytes_ = 0;  // guarded by mutex_
  // Guarded by mutex_: most recent first; key "<collection>/<index id>" for
  // db maps, "content/<key>/<heading>" for queries.
  std::list<std::pair<std::string, std::shared_ptr<const PreparedMap>>> entries_;
  std::unordered_map<std::string, decltype(entries_)::iterator> index_;
};

}  // namespace lmd::server
