#include "core/align/verify_hits.h"

#include <algorithm>

namespace lmd {

std::vector<VerifiedHit> VerifyHits(const PreparedQuery& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options) {
  std::vector<VerifiedHit> hits;
  hits.reserve(candidates.size());
  const size_t n_verify = options.max_candidates ? std::min(options.max_candidates, candidates.size())
                                                 : candidates.size();
  for (size_t i = 0; i < candidates.size(); ++i) {
    const HitCandidate& c = candidates[i];
    VerifiedHit h;
    h.map_id = c.map_id;
    h.retrieval_score = c.retrieval_score;
    h.retrieval_rank = i;
    if (i < n_verify) {
      h.verified = true;
      if (!c.guesses.empty()) h.match.pose = c.guesses[0];
      if (c.db) {
        auto score_of = [&](const ScanMatch& m) {
          return m.score > 0.0 ? m.score - options.conflict_weight * m.conflict_fraction : 0.0;
        };
        bool have = false;
        if (!c.guesses.empty()) {
          h.match = MatchLocalMaps(query, *c.db, c.guesses, options.match);
          h.score = score_of(h.match);
          have = true;
        }
        if (options.global_search && (!have || h.score < options.global_below_score)) {
          const ScanMatch global = MatchLocalMapsGlobal(query, *c.db, options.match);
          if (!have || score_of(global) > h.score) {
            h.match = global;
            h.score = score_of(global);
          }
        }
      }
    }
    hits.push_back(h);
  }
  std::stable_sort(hits.begin(), hits.end(), [](const VerifiedHit& a, const VerifiedHit& b) {
    if (a.verified != b.verified) return a.verified;
    if (!a.verified) return false;  // unverified: input order
    if (a.score != b.score) return a.score > b.score;
    return a.retrieval_score > b.retrieval_score;
  });
  return hits;
}

std::vector<VerifiedHit> VerifyHits(const LocalMap& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options) {
  return VerifyHits(PrepareQuery(query, options.match), candidates, options);
}

}  // namespace lmd
