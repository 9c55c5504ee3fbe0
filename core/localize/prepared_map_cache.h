// PreparedMapCache: stored maps prepared for scan matching (likelihood
// pyramids, buckets, free space: ~100-200 KB each, 1-5 ms to build), or
// gridded alone for a coarse fit (PreparedMap::SearchGridOnly, completed and
// replaced when matched against), kept in memory up to a byte budget, least
// recently used dropped first. Keyed by collection and the map's index id,
// which lmdd changes whenever a map is replaced, so an entry is never stale.
// lmdd (server/store_map_source.h) puts a map here when it is inserted
// (prepared anyway, with its place features) and finds it again when it is
// a hit; after a restart or an eviction it is prepared on first use.
// lmd-bench places serves its simulated store through it too. Thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

#include "core/align/prepared_map.h"

namespace lmd {

class PreparedMapCache {
 public:
  explicit PreparedMapCache(size_t capacity_bytes) : capacity_bytes_(capacity_bytes) {}

  // What a miss prepares from: the stored map and its compass heading.
  struct Source {
    LocalMap map;
    std::optional<double> heading;
  };
  // Reads the stored map on a miss; nullopt when it is no longer stored.
  using ReadSource = std::function<std::optional<Source>()>;

  // The map prepared for scan matching (PrepareMap): the one held, or
  // `read`'s prepared (a search grid held completed) and added. Null when
  // `read` finds nothing.
  std::shared_ptr<const PreparedMap> Prepared(const std::string& collection, uint64_t index_id,
                                              const PreparedMapOptions& options, const ReadSource& read);
  // At least its search grid (MapSource::SearchGrid): whatever is held, or
  // `read`'s points gridded (PrepareSearchGrid) and added.
  std::shared_ptr<const PreparedMap> SearchGrid(const std::string& collection, uint64_t index_id,
                                                const PreparedMapOptions& options, const ReadSource& read);

  // Null when absent.
  std::shared_ptr<const PreparedMap> Find(const std::string& collection, uint64_t index_id);
  // Adds (if it fits and is new, or completes a search grid held:
  // PreparedMap::SearchGridOnly) and drops the least recent beyond the budget.
  void Put(const std::string& collection, uint64_t index_id, std::shared_ptr<const PreparedMap> prepared);

  size_t bytes() const;
  size_t size() const;  // maps held
  // Find calls that found nothing, and maps dropped for the budget, since start.
  uint64_t misses() const { return misses_; }
  uint64_t evictions() const { return evictions_; }

 private:
  static std::string KeyOf(const std::string& collection, uint64_t index_id) {
    return collection + "/" + std::to_string(index_id);
  }

  const size_t capacity_bytes_;
  std::atomic<uint64_t> misses_{0};
  std::atomic<uint64_t> evictions_{0};
  mutable std::mutex mutex_;
  size_t bytes_ = 0;  // guarded by mutex_
  // Guarded by mutex_: most recent first.
  std::list<std::pair<std::string, std::shared_ptr<const PreparedMap>>> entries_;
  std::unordered_map<std::string, decltype(entries_)::iterator> index_;
};

}  // namespace lmd
