#include "core/localize/prepared_map_cache.h"

namespace lmd {

size_t PreparedMapCache::bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return bytes_;
}

size_t PreparedMapCache::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return index_.size();
}

std::shared_ptr<const PreparedMap> PreparedMapCache::Prepared(const std::string& collection, uint64_t index_id,
                                                              const PreparedMapOptions& options,
                                                              const ReadSource& read) {
  const std::shared_ptr<const PreparedMap> held = Find(collection, index_id);
  if (held && !held->SearchGridOnly()) return held;
  const std::optional<Source> source = read();
  if (!source) return nullptr;
  auto prepared = std::make_shared<const PreparedMap>(held ? CompletePreparation(*held, source->map, source->heading)
                                                           : PrepareMap(source->map, options, source->heading));
  Put(collection, index_id, prepared);
  return prepared;
}

std::shared_ptr<const PreparedMap> PreparedMapCache::SearchGrid(const std::string& collection, uint64_t index_id,
                                                                const PreparedMapOptions& options,
                                                                const ReadSource& read) {
  if (std::shared_ptr<const PreparedMap> held = Find(collection, index_id)) return held;
  const std::optional<Source> source = read();
  if (!source) return nullptr;
  auto grid = std::make_shared<const PreparedMap>(PrepareSearchGrid(source->map.points, options));
  Put(collection, index_id, grid);
  return grid;
}

std::shared_ptr<const PreparedMap> PreparedMapCache::Find(const std::string& collection, uint64_t index_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(KeyOf(collection, index_id));
  if (it == index_.end()) {
    ++misses_;
    return nullptr;
  }
  entries_.splice(entries_.begin(), entries_, it->second);
  return it->second->second;
}

void PreparedMapCache::Put(const std::string& collection, uint64_t index_id,
                           std::shared_ptr<const PreparedMap> prepared) {
  if (!prepared) return;
  const size_t size = prepared->MemoryBytes();
  const std::string key = KeyOf(collection, index_id);
  std::lock_guard<std::mutex> lock(mutex_);
  if (capacity_bytes_ == 0 || size > capacity_bytes_) return;
  const auto it = index_.find(key);
  if (it != index_.end()) {
    const std::shared_ptr<const PreparedMap>& held = it->second->second;
    if (!held->SearchGridOnly() || prepared->SearchGridOnly()) return;
    bytes_ -= held->MemoryBytes();  // a search grid completed: the complete map replaces it
    entries_.erase(it->second);
    index_.erase(it);
  }
  entries_.emplace_front(key, std::move(prepared));
  index_[key] = entries_.begin();
  bytes_ += size;
  while (bytes_ > capacity_bytes_) {
    bytes_ -= entries_.back().second->MemoryBytes();
    index_.erase(entries_.back().first);
    entries_.pop_back();
    ++evictions_;
  }
}

}  // namespace lmd
