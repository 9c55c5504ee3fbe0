// Geometric verification of retrieval hits: re-rank the index's top-N
// candidates by how well the query map's points align with each candidate's
// points (scan_match.h), and attach the refined metric pose.
//
// Policy: match each candidate within the windows around its guesses (the
// poses its retrieval hit implies, e.g. RelativePose for each orientation).
// Then, if global_search is on and no candidate scored matched_score or more
// that way, run the guess-free search for every candidate that scored below
// global_below_score (or had no guesses) and keep the better of the two. The
// guess-free search costs several guided ones; once one candidate matched
// well, it rarely changes the order of the top hits.
// Verification score = overlap score - conflict_weight * conflict
// fraction (query points the db map saw as free space) - reverse_conflict_weight
// * reverse conflict fraction (db points the query map saw as free space, when
// the query's own free space is given): a wrong place that shares walls with
// the query usually also puts walls in the other map's free space.
// Candidates are verified in input order; once enough_matches of them reached
// matched_score, the rest are not verified (in a store that holds many maps
// of the query's place, the first few confirm it and the others add little).
// Candidates are then ordered by verification score (descending), exact ties
// by retrieval score (descending), then by input order; candidates not
// verified (beyond max_candidates or after enough matches) follow in input order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "core/align/prepared_map.h"
#include "core/align/scan_match.h"
#include "core/types.h"

namespace lmd {

struct HitCandidate {
  uint64_t map_id = 0;
  std::shared_ptr<const PreparedMap> db;  // prepared db map; null = scores 0 (unless `prepare` gives one)
  double retrieval_score = 0.0;           // the index's score (tie-breaker)
  std::vector<Pose2> guesses;             // query own frame in db own frame; may be empty
  // When db is null: called once if the candidate is verified, so that only
  // verified candidates pay for preparing their map; may return null.
  std::function<std::shared_ptr<const PreparedMap>()> prepare;
};

struct VerifyOptions {
  ScanMatchOptions match;
  bool global_search = true;         // fall back to the guess-free search (see policy)
  double global_below_score = 0.5;   // guided verification score under which the guess-free search runs
  // No guess-free search at all once a candidate's guided verification score
  // reaches this (> 1 = never skip). 0.8: lmd-eval's best on orebro, fr101 and
  // intel kept the same place recall@1 and ran 2-28 % faster (docs/results.md).
  double matched_score = 0.8;
  // Weight of the free-space conflict fraction in the verification score. 2:
  // on intel / aces / fr079 (guess-free), score - 2 conflicts widened the gap
  // between the 10th percentile of true pairs and the 90th of wrong pairs in
  // all three logs (0.08 / 0.03 / -0.03 with the overlap alone -> 0.21 / 0.06 / 0.06).
  double conflict_weight = 2.0;
  // Weight of the reverse conflict fraction; used only when VerifyHits gets
  // the query prepared as a map (with its free space). 0 = not measured.
  double reverse_conflict_weight = 0.0;
  size_t max_candidates = 0;         // verify only the first N candidates (0 = all); the rest follow unverified
  size_t enough_matches = 0;         // stop verifying once N candidates reached matched_score (0 = never)
  // Asked before each scan match; once it returns true, no further candidate
  // is matched (they count as not verified), e.g. when the caller's request
  // was cancelled. Empty = never.
  std::function<bool()> stop;
};

struct VerifiedHit {
  uint64_t map_id = 0;
  double retrieval_score = 0.0;
  size_t retrieval_rank = 0;  // position in the input
  bool verified = false;      // false beyond max_candidates or after enough_matches
  double score = 0.0;         // verification score (see policy); 0 if unverified or unmatchable
  ScanMatch match;            // pose (query own frame in db own frame), overlap, conflicts
  double reverse_conflict_fraction = 0.0;  // db points in the query's free space (when measured)
  std::shared_ptr<const PreparedMap> db;  // the db map as matched (verified only; may be null)
};

// Candidates re-ordered as described above; never fails (degenerate maps score 0).
std::vector<VerifiedHit> VerifyHits(const LocalMap& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options = {});
// `query_map`: the query prepared as a map (PrepareMap, with free space), for
// reverse conflicts; may be null.
std::vector<VerifiedHit> VerifyHits(const PreparedQuery& query, const std::vector<HitCandidate>& candidates,
                                    const VerifyOptions& options = {}, const PreparedMap* query_map = nullptr);

}  // namespace lmd
