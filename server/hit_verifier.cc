#include "server/hit_verifier.h"

#include <cstring>

#include "core/align/relative_pose.h"
#include "server/indexing.h"
#include "proto/convert.h"

namespace lmd::server {
namespace {

// Cache key of a map prepared as a query: its content and planned heading.
std::string ContentKey(const DescriptorCache::Key& key, double heading) {
  uint64_t heading_bits = 0;
  static_assert(sizeof heading_bits == sizeof heading);
  std::memcpy(&heading_bits, &heading, sizeof heading);
  return "content/" + std::to_string(key.a) + "/" + std::to_string(key.b) + "/" + std::to_string(key.size) + "/" +
         std::to_string(heading_bits);
}

}  // namespace

size_t HitVerifier::cached_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return cached_bytes_;
}

std::shared_ptr<const PreparedMap> HitVerifier::Find(const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return nullptr;
  entries_.splice(entries_.begin(), entries_, it->second);
  return it->second->second;
}

std::shared_ptr<const PreparedMap> HitVerifier::Take(const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return nullptr;
  std::shared_ptr<const PreparedMap> prepared = std::move(it->second->second);
  cached_bytes_ -= prepared->MemoryBytes();
  entries_.erase(it->second);
  index_.erase(it);
  return prepared;
}

void HitVerifier::Put(const std::string& key, std::shared_ptr<const PreparedMap> prepared) {
  const size_t bytes = prepared->MemoryBytes();
  std::lock_guard<std::mutex> lock(mutex_);
  if (capacity_bytes_ == 0 || bytes > capacity_bytes_ || index_.count(key) != 0) return;
  entries_.emplace_front(key, std::move(prepared));
  index_[key] = entries_.begin();
  cached_bytes_ += bytes;
  while (cached_bytes_ > capacity_bytes_) {
    cached_bytes_ -= entries_.back().second->MemoryBytes();
    index_.erase(entries_.back().first);
    entries_.pop_back();
  }
}

std::shared_ptr<const PreparedMap> HitVerifier::Prepare(const LocalMap& map, double heading) {
  ++maps_prepared_;
  return std::make_shared<const PreparedMap>(PrepareMap(map, PreparedMapOptions(), heading));
}

Result<std::shared_ptr<const PreparedMap>> HitVerifier::Prepared(const std::string& collection,
                                                                 const StoreHit& hit, double heading) {
  const std::string key = collection + "/" + std::to_string(hit.hit.map_id);
  if (std::shared_ptr<const PreparedMap> cached = Find(key)) return cached;
  Result<v1::StoredMap> stored = store_->GetMap(collection, hit.map_id);
  if (!stored.ok()) return stored.status();
  std::shared_ptr<const PreparedMap> prepared;
  if (query_maps_kept_) {  // hashing the stored map costs about 5 % of preparing it
    prepared = Take(ContentKey(DescriptorCache::KeyOf(stored->map().SerializeAsString()), heading));
  }
  if (!prepared) prepared = Prepare(MethodView(FromProto(stored->map())), heading);
  Put(key, prepared);
  return prepared;
}

Result<std::vector<VerifiedStoreHit>> HitVerifier::Verify(const std::string& collection, const LocalMap& query,
                                                          const DescriptorCache::Key& query_key, const Lmd& query_lmd,
                                                          const std::vector<StoreHit>& hits,
                                                          size_t candidates, size_t enough_matches,
                                                          double reverse_conflict_weight,
                                                          const std::function<bool()>& cancelled) {
  candidates = std::min(candidates, hits.size());
  std::vector<HitCandidate> inputs;
  for (size_t i = 0; i < candidates; ++i) {
    const StoreHit& hit = hits[i];
    HitCandidate candidate;
    candidate.map_id = i;  // position in `hits`
    candidate.retrieval_score = hit.hit.score;
    Result<Lmd> db = store_->GetDescriptor(collection, hit.map_id);
    if (!db.ok()) {  // deleted meanwhile: scores 0
      inputs.push_back(std::move(candidate));
      continue;
    }
    candidate.guesses = {RelativePose(query_lmd.frame, db->frame, hit.hit.orientation, hit.hit.offset)};
    // Prepared only if verified (enough matches may stop before it); the
    // lambda refers to this call's arguments, so `inputs` must not outlive it.
    candidate.prepare = [this, &collection, &hit, heading = db->frame.heading] {
      Result<std::shared_ptr<const PreparedMap>> prepared = Prepared(collection, hit, heading);
      return prepared.ok() ? std::move(prepared).value() : nullptr;
    };
    inputs.push_back(std::move(candidate));
  }
  std::vector<VerifiedStoreHit> out;
  VerifyOptions options;
  // As lmd-eval's "best": the index already chose the best of the four
  // orientations, so the guided search stays near its guess (a quarter-turn
  // search costs 4x and the guess-free fallback still covers a wrong turn).
  options.match.quarter_turns = false;
  options.enough_matches = enough_matches;
  options.reverse_conflict_weight = reverse_conflict_weight;
  options.stop = cancelled;
  const PreparedQuery prepared_query = PrepareQuery(query, options.match, query_lmd.frame.heading);
  // The query's own free space, for reverse conflicts (one db map's preparation).
  std::shared_ptr<const PreparedMap> query_map;
  if (reverse_conflict_weight > 0 && !inputs.empty()) {
    // The heading rounded as the store keeps it (lmd_codec: float), so that
    // this preparation equals the one of the same map once stored.
    const double heading = static_cast<float>(query_lmd.frame.heading);
    const std::string key = ContentKey(query_key, heading);
    query_map = Find(key);
    if (!query_map) {
      query_map = Prepare(query, heading);
      Put(key, query_map);
      query_maps_kept_ = true;
    }
  }
  std::vector<VerifiedHit> verified_hits = VerifyHits(prepared_query, inputs, options, query_map.get());
  if (cancelled && cancelled()) return Status::Cancelled("call cancelled during verification");
  for (VerifiedHit& verified : verified_hits) {
    VerifiedStoreHit hit;
    hit.hit = hits[verified.map_id];
    hit.verified = verified.verified && verified.score > 0;
    hit.score = verified.verified ? verified.score : hit.hit.hit.score;
    hit.pose = verified.match.pose;
    if (hit.verified) hit.prepared = std::move(verified.db);
    out.push_back(std::move(hit));
  }
  for (size_t i = candidates; i < hits.size(); ++i) out.push_back({hits[i], false, hits[i].hit.score, {}, nullptr});
  return out;
}

}  // namespace lmd::server
