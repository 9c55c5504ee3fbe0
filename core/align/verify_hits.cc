#include "core/align/verify_hits.h"

#include <algorithm>

#include "core/localmap/pose_ops.h"

namespace lmd {

std::vector<VerifiedHit> VerifyHits(const PreparedQuery& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options, const PreparedMap* query_map) {
  const bool reverse = query_map != nullptr && !query_map->empty() && options.reverse_conflict_weight > 0.0;
  // Fraction of db points that the aligned query map saw as free space.
  auto reverse_conflicts = [&](const ScanMatch& m, const PreparedMap& db) {
    if (!reverse || m.score <= 0.0) return 0.0;
    return MeasureOverlap(db.points, *query_map, Inverse(m.pose), options.match.inlier_radius_m).conflict_fraction;
  };
  auto score_of = [&](const ScanMatch& m, double reverse_fraction) {
    return m.score > 0.0 ? m.score - options.conflict_weight * m.conflict_fraction -
                               options.reverse_conflict_weight * reverse_fraction
                         : 0.0;
  };
  std::vector<VerifiedHit> hits;
  hits.reserve(candidates.size());
  const size_t n_verify = options.max_candidates ? std::min(options.max_candidates, candidates.size())
                                                 : candidates.size();
  size_t matches = 0;  // candidates that reached matched_score near their guesses
  bool stopped = false;
  auto stop = [&] { return stopped || (stopped = options.stop && options.stop()); };
  for (size_t i = 0; i < candidates.size(); ++i) {
    const HitCandidate& c = candidates[i];
    VerifiedHit h;
    h.map_id = c.map_id;
    h.retrieval_score = c.retrieval_score;
    h.retrieval_rank = i;
    h.verified = i < n_verify && (options.enough_matches == 0 || matches < options.enough_matches) && !stop();
    if (h.verified) h.db = c.db ? c.db : c.prepare ? c.prepare() : nullptr;
    if (h.verified && !c.guesses.empty()) {
      h.match.pose = c.guesses[0];
      if (h.db) {
        h.match = MatchLocalMaps(query, *h.db, c.guesses, options.match);
        h.reverse_conflict_fraction = reverse_conflicts(h.match, *h.db);
        h.score = score_of(h.match, h.reverse_conflict_fraction);
        if (h.score >= options.matched_score) ++matches;
      }
    }
    hits.push_back(std::move(h));
  }
  if (options.global_search && matches == 0) {
    for (size_t i = 0; i < n_verify; ++i) {
      const HitCandidate& c = candidates[i];
      VerifiedHit& h = hits[i];
      if (!h.db || (!c.guesses.empty() && h.score >= options.global_below_score)) continue;
      if (stop()) break;
      const ScanMatch global = MatchLocalMapsGlobal(query, *h.db, options.match);
      const double global_reverse = reverse_conflicts(global, *h.db);
      if (c.guesses.empty() || score_of(global, global_reverse) > h.score) {
        h.match = global;
        h.reverse_conflict_fraction = global_reverse;
        h.score = score_of(global, global_reverse);
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
