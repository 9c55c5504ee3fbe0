#include "core/align/verify_hits.h"

#include <algorithm>

namespace lmd {

std::vector<VerifiedHit> VerifyHits(const PreparedQuery& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options) {
  auto score_of = [&](const ScanMatch& m) {
    return m.score > 0.0 ? m.score - options.conflict_weight * m.conflict_fraction : 0.0;
  };
  std::vector<VerifiedHit> hits;
  hits.reserve(candidates.size());
  const size_t n_verify = options.max_candidates ? std::min(options.max_candidates, candidates.size())
                                                 : candidates.size();
  size_t matches = 0;  // candidates that reached matched_score near their guesses
  std::vector<std::shared_ptr<const PreparedMap>> dbs(candidates.size());
  for (size_t i = 0; i < candidates.size(); ++i) {
    const HitCandidate& c = candidates[i];
    VerifiedHit h;
    h.map_id = c.map_id;
    h.retrieval_score = c.retrieval_score;
    h.retrieval_rank = i;
    h.verified = i < n_verify && (options.enough_matches == 0 || matches < options.enough_matches);
    if (h.verified) {
      dbs[i] = c.db ? c.db : c.prepare ? c.prepare() : nullptr;
      h.db = dbs[i];
    }
    if (h.verified && !c.guesses.empty()) {
      h.match.pose = c.guesses[0];
      if (dbs[i]) {
        h.match = MatchLocalMaps(query, *dbs[i], c.guesses, options.match);
        h.score = score_of(h.match);
        if (h.score >= options.matched_score) ++matches;
      }
    }
    hits.push_back(h);
  }
  if (options.global_search && matches == 0) {
    for (size_t i = 0; i < n_verify; ++i) {
      const HitCandidate& c = candidates[i];
      VerifiedHit& h = hits[i];
      if (!dbs[i] || (!c.guesses.empty() && h.score >= options.global_below_score)) continue;
      const ScanMatch global = MatchLocalMapsGlobal(query, *dbs[i], options.match);
      if (c.guesses.empty() || score_of(global) > h.score) {
        h.match = global;
        h.score = score_of(global);
      }
    }
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
