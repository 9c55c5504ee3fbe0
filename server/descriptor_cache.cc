#include "server/descriptor_cache.h"

#include <functional>
#include <string_view>

namespace lmd::server {

DescriptorCache::Key DescriptorCache::KeyOf(const std::string& map_bytes) {
  Key key;
  key.a = std::hash<std::string_view>()(map_bytes);
  uint64_t fnv = 0xcbf29ce484222325ULL;  // FNV-1a, independent of std::hash
  for (unsigned char c : map_bytes) fnv = (fnv ^ c) * 0x100000001b3ULL;
  key.b = fnv;
  key.size = map_bytes.size();
  return key;
}

std::optional<Lmd> DescriptorCache::Find(const Key& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return std::nullopt;
  entries_.splice(entries_.begin(), entries_, it->second);
  return it->second->second;
}

void DescriptorCache::Put(const Key& key, const Lmd& lmd) {
  if (capacity_ == 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (const auto it = index_.find(key); it != index_.end()) {
    entries_.splice(entries_.begin(), entries_, it->second);
    return;
  }
  entries_.emplace_front(key, lmd);
  index_[key] = entries_.begin();
  if (entries_.size() > capacity_) {
    index_.erase(entries_.back().first);
    entries_.pop_back();
  }
}

}  // namespace lmd::server
