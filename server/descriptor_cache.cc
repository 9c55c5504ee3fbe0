#include "server/descriptor_cache.h"

#include <functional>
#include <string_view>

#include "core/util/fnv1a.h"

namespace lmd::server {

DescriptorCache::Key DescriptorCache::KeyOf(const std::string& map_bytes) {
  Key key;
  key.a = std::hash<std::string_view>()(map_bytes);
  key.b = Fnv1a64(map_bytes);  // independent of std::hash
  key.size = map_bytes.size();
  return key;
}

std::shared_ptr<const DescribedMap> DescriptorCache::Find(const Key& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return nullptr;
  entries_.splice(entries_.begin(), entries_, it->second);
  return it->second->second;
}

void DescriptorCache::Put(const Key& key, std::shared_ptr<const DescribedMap> described) {
  if (capacity_ == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (const auto it = index_.find(key); it != index_.end()) {
    if (described->lmd && !it->second->second->lmd) it->second->second = std::move(described);
    entries_.splice(entries_.begin(), entries_, it->second);
    return;
  }
  entries_.emplace_front(key, std::move(described));
  index_[key] = entries_.begin();
  if (entries_.size() > capacity_) {
    index_.erase(entries_.back().first);
    entries_.pop_back();
  }
}

}  // namespace lmd::server
