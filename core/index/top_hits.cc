#include "core/index/top_hits.h"

#include <algorithm>

namespace lmd {

void TopHits::Offer(const MapHit& hit) {
  if (!(hit.score > 0.0)) return;
  if (full() && !RanksBefore(hit, hits_.back())) return;
  auto it = std::upper_bound(hits_.begin(), hits_.end(), hit, RanksBefore);
  hits_.insert(it, hit);
  if (hits_.size() > k_) hits_.pop_back();
}

std::vector<MapHit> TopHits::Take() {
  for (size_t r = 0; r < hits_.size(); ++r) hits_[r].rank = r;
  return std::move(hits_);
}

}  // namespace lmd
