// Keeping the best k hits in rank order (score descending, then map id
// ascending); shared by the inverted file and the exhaustive scorer.
#pragma once

#include <cstddef>
#include <vector>

#include "core/index/retrieve_options.h"

namespace lmd {

// True when a ranks before b.
inline bool RanksBefore(const MapHit& a, const MapHit& b) {
  if (a.score != b.score) return a.score > b.score;
  return a.map_id < b.map_id;
}

class TopHits {
 public:
  explicit TopHits(size_t k) : k_(k) {}
  // Offers a hit; hits with score <= 0 are ignored.
  void Offer(const MapHit& hit);
  bool full() const { return hits_.size() >= k_; }
  // Score of the k-th hit (valid when full()).
  double kth_score() const { return hits_.back().score; }
  // The hits in rank order with rank filled in.
  std::vector<MapHit> Take();

 private:
  size_t k_;
  std::vector<MapHit> hits_;  // sorted by RanksBefore, size <= k_
};

}  // namespace lmd
