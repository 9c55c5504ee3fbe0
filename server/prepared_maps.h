// PreparedMapCache: stored maps prepared for scan matching (likelihood
// pyramids, buckets, free space: ~100-200 KB each, 1-5 ms to build), or
// gridded alone for a coarse fit (PreparedMap::SearchGridOnly, completed and
// replaced when matched against), kept in memory up to a byte budget, least
// recently used dropped first. Keyed by
// collection and the map's index id, which changes whenever a map is
// replaced, so an entry is never stale. A map is put here when it is
// inserted (prepared anyway, with its place features) and found again when
// it is a hit; after a restart or an eviction it is prepared on first use.
// Thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "core/align/prepared_map.h"

namespace lmd::server {

class PreparedMapCache {
 public:
  explicit PreparedMapCache(size_t capacity_bytes) : capacity_bytes_(capacity_bytes) {}

  // Null when absent.
  std::shared_ptr<const PreparedMap> Find(const std::string& collection, uint64_t index_id);
  // Adds (if it fits and is new, or completes a search grid held:
  // PreparedMap::SearchGridOnly) and drops the least recent beyond the budget.
  void Put(const std::string& collection, uint64_t index_id, std::shared_ptr<const PreparedMap> prepared);

  size_t bytes() const;
  // Find calls that found nothing, since start.
  uint64_t misses() const { return misses_; }

 private:
  static std::string KeyOf(const std::string& collection, uint64_t index_id) {
    return collection + "/" + std::to_string(index_id);
  }

  const size_t capacity_bytes_;
  std::atomic<uint64_t> misses_{0};
  mutable std::mutex mutex_;
  size_t bytes_ = 0;  // guarded by mutex_
  // Guarded by mutex_: most recent first.
  std::list<std::pair<std::string, std::shared_ptr<const PreparedMap>>> entries_;
  std::unordered_map<std::string, decltype(entries_)::iterator> index_;
};

}  // namespace lmd::server
