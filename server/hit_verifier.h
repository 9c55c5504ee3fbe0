// HitVerifier: the product default method's second stage. The index's best
// candidates are verified geometrically (core/align/verify_hits.h: the query's
// points aligned onto each candidate's points by our scan matcher) and
// re-ranked by aligned overlap; each verified hit gets the scan matcher's
// metric pose. Prepared db maps (likelihood pyramids, ~100-200 KB each, 1-5 ms
// to build) are kept in an LRU cache of bounded bytes keyed by the map's index id, which
// changes whenever a map is replaced, so a cached entry is never stale.
#pragma once

#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/align/verify_hits.h"
#include "core/status.h"
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
  // frame for the index's pose guesses.
  Result<std::vector<VerifiedStoreHit>> Verify(const std::string& collection, const LocalMap& query,
                                               const Lmd& query_lmd, const std::vector<StoreHit>& hits,
                                               size_t candidates, size_t enough_matches,
                                               double reverse_conflict_weight);

 private:
  // The prepared db map of a hit, from the cache or built from the store;
  // `heading` is its planned frame's heading (the same entropy compass).
  Result<std::shared_ptr<const PreparedMap>> Prepared(const std::string& collection, const StoreHit& hit,
                                                      double heading);

  const MapStore* const store_;
  const size_t capacity_bytes_;
  std::mutex mutex_;
  size_t cached_bytes_ = 0;  // guarded by mutex_
  // Guarded by mutex_: most recent first; key "<collection>/<index id>".
  std::list<std::pair<std::string, std::shared_ptr<const PreparedMap>>> entries_;
  std::unordered_map<std::string, decltype(entries_)::iterator> index_;
};

}  // namespace lmd::server
