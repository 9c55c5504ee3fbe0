#include "server/recent_fixes.h"

namespace lmd::server {

void RecentFixes::Put(const std::string& collection, const DescriptorCache::Key& map, const v1::MapAnchor& anchor) {
  if (capacity_ == 0) return;
  const std::string key = KeyOf(collection, map);
  std::lock_guard<std::mutex> lock(mutex_);
  if (const auto it = index_.find(key); it != index_.end()) {
    it->second->second = anchor;
    entries_.splice(entries_.begin(), entries_, it->second);
    return;
  }
  entries_.emplace_front(key, anchor);
  index_[key] = entries_.begin();
  if (entries_.size() > capacity_) {
    index_.erase(entries_.back().first);
    entries_.pop_back();
  }
}

std::optional<v1::MapAnchor> RecentFixes::Find(const std::string& collection, const DescriptorCache::Key& map) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(KeyOf(collection, map));
  if (it == index_.end()) return std::nullopt;
  return it->second->second;
}

}  // namespace lmd::server
