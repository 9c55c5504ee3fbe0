// DescriptorCache: what lmdd computed from recently seen local maps, by
// content. A robot typically sends the same map twice in a row
// (DetectChanges, then InsertMaps, or the reverse); describing and preparing
// costs milliseconds (viewpoint planning, histograms, ray casting), looking
// it up here microseconds. Keyed by two independent 64-bit hashes of the
// map's wire bytes plus their length, so a wrong hit needs a 128-bit
// collision. Thread-safe; least recently used entries are dropped beyond
// `capacity`.
#pragma once

#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "server/indexing.h"

namespace lmd::server {

class DescriptorCache {
 public:
  explicit DescriptorCache(size_t capacity) : capacity_(capacity) {}

  struct Key {
    uint64_t a = 0, b = 0, size = 0;
    bool operator==(const Key& o) const { return a == o.a && b == o.b && size == o.size; }
  };
  static Key KeyOf(const std::string& map_bytes);

  // Null when absent.
  std::shared_ptr<const DescribedMap> Find(const Key& key);
  // Of two entries for one key, keeps the one with the paper's descriptor.
  void Put(const Key& key, std::shared_ptr<const DescribedMap> described);

 private:
  struct KeyHash {
    size_t operator()(const Key& k) const { return static_cast<size_t>(k.a ^ (k.b * 0x9e3779b97f4a7c15ULL)); }
  };
  using Entry = std::pair<Key, std::shared_ptr<const DescribedMap>>;

  const size_t capacity_;
  std::mutex mutex_;
  std::list<Entry> entries_;  // most recent first; guarded by mutex_
  std::unordered_map<Key, std::list<Entry>::iterator, KeyHash> index_;  // guarded by mutex_
};

}  // namespace lmd::server
