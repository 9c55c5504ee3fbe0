// The steps the localisation entry points share (localizer.h, prior.h,
// sequence.h): scan matching of chosen maps, ranking, and the verdict with
// its change masks. Internal to core/localize.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_set>
#include <vector>

#include "core/localize/localizer.h"

namespace lmd::localize_internal {

// A stored map to verify and where to look in it.
struct Candidate {
  uint64_t map_id = 0;
  std::vector<Pose2> guesses;  // query own frame in the map's own frame
  double votes = 0.0;          // first stage (0 when it did not run)
  size_t first_rank = 0;
};

// How far the query's points (those the search matches) lie from its own
// origin, m: where a prior puts the origin, the points lie within this.
double QueryReach(const LocalQuery& query);

// `options` whose scan matches give up once `stop` returns true (a caller's
// deadline or cancellation), not only between them.
LocalizeOptions WithStop(const LocalizeOptions& options, const std::function<bool()>& stop);
// Whether the stop WithStop gave `options` asks to give up (none: never).
bool StopAsked(const LocalizeOptions& options);

// The hit of a scan match: its pose, shares and verification score.
LocalizedHit Scored(const LocalQuery& query, const PreparedMap& db, const ScanMatch& m, const LocalizeOptions& options);
// The hit at `pose`, measured as verification measures (no search).
LocalizedHit ScoredAt(const LocalQuery& query, const PreparedMap& db, const Pose2& pose, const LocalizeOptions& options);

// The verification score of the best hit's map at its best other pose
// (beyond options.self_rival_radius_m / self_rival_angle_deg, anywhere in
// the map): a self-rival for a sure answer judged by `verdict`. Poses that
// could not score above HighestHarmlessRival are not searched for (0).
double OtherPoseScore(const LocalQuery& query, const LocalizedHit& best, const LocalizeOptions& options,
                      const ConfidenceOptions& verdict);

// OtherPoseScore as Conclude's second_pose; empty where
// options.self_rival_radius_m is 0. Holds references to its arguments.
std::function<double(const LocalizedHit& best)> OtherPoseRival(const LocalQuery& query, const LocalizeOptions& options,
                                                               const ConfidenceOptions& verdict);

// How firmly `best`'s map pins the query's pose at the precision a sure
// answer promises (verdict.max_pose_spread_m): the share of the query's
// points within a third of inlier_radius_m of the map's at the pose, less
// the most of them that stay that close with the pose slid
// max_pose_spread_m in any of eight directions. A corridor whose walls run
// on past the query keeps nearly all of them sliding along it (about 0); a
// room loses at least its cross walls' points to any slide.
double SlideMargin(const LocalQuery& query, const LocalizedHit& best, const LocalizeOptions& options,
                   const ConfidenceOptions& verdict);

// The query's site pose as the maps that show its place measure it: each
// agreeing anchored hit that fits (options.min_score; the best hit always)
// is one measurement, through its own match and its own anchor. The mean of
// those within max_pose_spread_m / _deg of their median, when at least
// three are; else none (the best hit's pose stands).
std::optional<Pose2> FusedSitePose(const std::vector<LocalizedHit>& hits, const ConfidenceOptions& options);

// How well the query's points could fit `db` near `guess` (query own frame
// in db's): CorrelativeBound at the guess' turn over +-window_m, from blocks
// of at most block_m.
double FitNear(const LocalQuery& query, const PreparedMap& db, const Pose2& guess, double window_m, double block_m);

// The hypotheses of the first max_maps maps, in order of the query's fit
// near each (FitNear within options.match.window_m, from blocks of
// block_m; LocalizeOptions::fit_rank_maps), then the others as they were.
// `read` (optional) gains the ids of the maps whose grids it read.
void RankByFit(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options, size_t max_maps,
               double block_m, std::vector<PlaceHypothesis>* hypotheses, std::unordered_set<uint64_t>* read = nullptr);

// A map passed over for chosen route neighbours, with its guesses.
struct PassedOver {
  Candidate candidate;
  std::vector<uint64_t> for_maps;  // the chosen neighbours it was passed over for
};

// The maps to verify (at most options.verify_maps), in order of their best
// hypothesis, each with all its hypotheses as guesses; route neighbours of
// chosen maps passed over (into `passed`, when given, in the same order).
// Where maps without anchors are among them, anchored maps of
// `anchored_pool` (default: `hypotheses`) at places in the site none of them
// names follow, until options.verify_anchored_maps are anchored.
std::vector<Candidate> ChooseCandidates(const LocalQuery& query, const MapSource& source,
                                        const std::vector<PlaceHypothesis>& hypotheses, const LocalizeOptions& options,
                                        std::vector<PassedOver>* passed = nullptr,
                                        const std::vector<PlaceHypothesis>* anchored_pool = nullptr);

// The first options.passed_over_retries of `passed` whose chosen neighbours
// all fit worse than confidence.min_score in `hits` (or were not matched):
// passing a map over assumes its neighbour shows what it shows, and a
// neighbour that fits that badly did not.
std::vector<Candidate> PassedOverFailedFits(const std::vector<PassedOver>& passed,
                                            const std::vector<LocalizedHit>& hits, const LocalizeOptions& options);

// `hits` as the verdict sees them (confidence.h), in the same order.
std::vector<JudgedHit> AsJudged(const std::vector<LocalizedHit>& hits);

// The fit hits are ranked by: the score with options.closeness_weight of
// the share replaced by the closeness.
double RankFit(const LocalizedHit& hit, const LocalizeOptions& options);

// Best first: RankFit, then score, then the closer fit, then the map id.
void SortHits(std::vector<LocalizedHit>* hits, const LocalizeOptions& options);

// Scan matches each candidate near its guesses with `match` (options.match,
// or a wider window), best hits first (SortHits). Stops once options' stop
// says so (StopAsked); counts into stats.
std::vector<LocalizedHit> VerifyCandidates(const LocalQuery& query, const MapSource& source,
                                           const std::vector<Candidate>& candidates, const LocalizeOptions& options,
                                           const ScanMatchOptions& match, LocalizeStats* stats);

// ChooseCandidates, then the chosen verified with `match`, then
// PassedOverFailedFits verified too (none once the stop cut the first round
// short), best hits first. `verified` (optional) receives the candidates;
// `anchored_pool` as for ChooseCandidates.
std::vector<LocalizedHit> ChooseAndVerify(const LocalQuery& query, const MapSource& source,
                                          const std::vector<PlaceHypothesis>& hypotheses,
                                          const LocalizeOptions& options, const ScanMatchOptions& match,
                                          LocalizeStats* stats, std::vector<Candidate>* verified = nullptr,
                                          const std::vector<PlaceHypothesis>* anchored_pool = nullptr);

// What SearchAndVerify chose (lmd-eval global-misses reads it).
struct SearchTrace {
  std::vector<PlaceHypothesis> hypotheses;  // the first stage's (both rounds')
  std::vector<Candidate> verified;          // chosen, then retried (PassedOverFailedFits), then the second round's
};

// The first stage and the verification of the maps it names (route
// neighbours passed over, those of failed fits retried; where none fits, a
// second round, LocalizeOptions::second_round_hypotheses), best hits first:
// Localize without its verdict. `trace` (optional) receives its choices.
std::vector<LocalizedHit> SearchAndVerify(const LocalQuery& query, const MapSource& source,
                                          const LocalizeOptions& options, const std::function<bool(uint64_t)>& excluded,
                                          LocalizeStats* stats, SearchTrace* trace = nullptr);

// The maps of the answer's place: the hits agreeing with the best (within
// the agreement window), each with the query's pose in it. Change masks are
// made against them.
std::vector<AlignedMap> PlaceMaps(const std::vector<LocalizedHit>& hits, double best_score,
                                  const LocalizeOptions& options);

// How the query fits those maps together: the verification score's overlap
// less conflict_weight times its conflicts, over their union (a query point
// is explained by any of them; a conflict lies in one's free space and is
// explained by none).
double PlaceFit(const LocalQuery& query, const std::vector<AlignedMap>& place, const LocalizeOptions& options);

// Whether an answer that is not sure still gets change masks: its place
// fits (the best hit's score, or with changes_place_fit_before_conflicts its
// overlap, or its `place` maps together with
// changes_place_fit_of_union, reaches the verdict's min_score) and, but for
// a prior's answer (`prior_place`: LocalizeOptions::prior_changes_without_margin),
// no disagreeing hit comes within the verdict's min_margin. `hits` best
// first; `place`: PlaceMaps of them.
bool PlaceClear(const LocalQuery& query, const std::vector<LocalizedHit>& hits, const Verdict& verdict,
                const std::vector<AlignedMap>& place, const LocalizeOptions& options, bool prior_place);

// The anchored maps an answer with a site pose also makes its change masks
// against (LocalizeOptions::changes_site_maps), and the maps `excluded`
// leaves out.
struct SiteMaps {
  const MapSource* source = nullptr;
  const std::function<bool(uint64_t)>* excluded = nullptr;
};

// `place` and, of the changes_site_maps anchored maps (none `excluded`)
// whose robots drove nearest the query's path at `best`'s site pose, those
// not in it, each at the pose its anchor gives the query and credited to
// `best` (lmdd sends masks under returned hits). `place` alone where `best`
// has no site pose. *kept holds the maps added.
std::vector<AlignedMap> WithSiteMaps(const LocalQuery& query, const LocalizedHit& best, std::vector<AlignedMap> place,
                                     const SiteMaps& site, const LocalizeOptions& options,
                                     std::vector<std::shared_ptr<const PreparedMap>>* kept);

// The best hit refined, the verdict (with `second_pose`, when set and the
// verdict would be sure: the best map's score at another pose, a rival),
// the change masks when asked and sure or the place is clear (`prior_place`:
// a prior answered for the place, LocalizeOptions::prior_changes_without_margin;
// `site_maps`: where the best hit has a site pose, against those maps too),
// and the hits cut to top_k (the hit giving the site pose kept after them).
void Conclude(const LocalQuery& query, const LocalizeOptions& options, std::vector<LocalizedHit> hits,
              const std::function<double(const LocalizedHit& best)>& second_pose, bool with_changes,
              Localization* out, bool prior_place, const SiteMaps& site_maps);

// Sets each hit's collection_pose from its map's anchor, where it has one.
void SetCollectionPoses(const MapSource& source, std::vector<LocalizedHit>* hits);

}  // namespace lmd::localize_internal
