// RecentFixes: where lmdd has just localised a map surely in its
// collection's frame, by the map's content. A robot usually asks about its
// newest map (DetectChanges) and then stores it; when that answer was sure
// against an anchored map, the stored map is anchored too (a derived
// anchor), so that a collection grows its site map from a few anchored maps.
// Thread-safe; least recently used entries are dropped beyond `capacity`.
#pragma once

#include <list>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>

#include "lmd/v1/lmd.pb.h"
#include "server/descriptor_cache.h"

namespace lmd::server {

class RecentFixes {
 public:
  explicit RecentFixes(size_t capacity) : capacity_(capacity) {}

  void Put(const std::string& collection, const DescriptorCache::Key& map, const v1::MapAnchor& anchor);
  std::optional<v1::MapAnchor> Find(const std::string& collection, const DescriptorCache::Key& map);

 private:
  static std::string KeyOf(const std::string& collection, const DescriptorCache::Key& map) {
    return collection + "/" + std::to_string(map.a) + "/" + std::to_string(map.b) + "/" + std::to_string(map.size);
  }
  const size_t capacity_;
  std::mutex mutex_;
  std::list<std::pair<std::string, v1::MapAnchor>> entries_;  // most recent first; guarded by mutex_
  std::unordered_map<std::string, decltype(entries_)::iterator> index_;  // guarded by mutex_
};

}  // namespace lmd::server
