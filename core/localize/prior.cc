#include "core/localize/prior.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_set>

#include "core/align/correlative_search.h"
#include "core/align/icp.h"
#include "core/localize/site_grid.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

using namespace localize_internal;

namespace {

constexpr size_t kBoundedPerMatched = 4;  // maps nearest the query's path bounded per map matched
// Blocks of the bound that ranks them (CorrelativeBound), m. The coarsest
// level that covers a loose prior's window (6.4 m blocks) lights up nearly
// every map near the place; 1.6 m blocks tell the maps that show the query
// from those that only neighbour it. lmd-eval prior-misses, tuning logs
// (aces, fr079, intel, orebro): 25 -> 19 misses of 1245 (0.8 m: 18, 3.2 m:
// 20); held out 137 -> 114 of 3453; tracking priors, all logs, 115 -> 109.
// Bounding 6 instead of 4 maps per map matched then: 18 and 113. Served
// (lmd-eval served --mode prior): place@1 .975 -> .982 (held out .972 ->
// .978), sure and wrong 58 -> 61, CPU +2 %.
constexpr double kBoundBlockM = 1.6;
constexpr size_t kPriorHypotheses = 200;  // first-stage hypotheses over the maps near the prior
// Stored features the first stage reads over the maps near the prior, at
// most: it reads the buckets of the whole collection and passes over the
// other maps' features, so its cost grows with the site, not with the
// prior's region. Rarest query features first, as in a global search.
// Measured in process (against 100k, a global search's bound): fr079
// (tuning) search 5.2 -> 3.1 ms per query, place@1 .955 -> .962; frcampus
// (held out, the largest site, looked at for this choice) 2.5 -> 1.2 ms,
// .914 -> .911. A third of that (10k) cost frcampus a point (.904).
constexpr size_t kPriorStageReads = 30000;
// Vote peaks per map: the prior already bounds where the query is, so the
// global search's many peaks along a corridor (place_index.h) add cost and
// no place (served prior run, all logs: place@1 .948 -> .950 with 8).
constexpr size_t kPriorPeaksPerMap = 2;
// A loose prior stops verifying its nearest maps once they make a sure
// answer that at least this many besides the best agree with and fit: only
// then has Judge checked where they put the query against the best's pose
// (ConfidenceOptions::max_pose_spread_m; confidence.cc).
constexpr size_t kConfirmingMaps = 2;
constexpr double kStageSlackM = 0.5;      // m, added to the scan match window around them
// The first stage's maps near the prior: at most this many of each 10 m
// cell, the newest (anchor_index.h). A bound on cost where a fleet piles up
// maps; the busiest cell of the nine logs of ../shared/data holds 370, so it
// changes nothing there.
constexpr size_t kStageMapsPerCell = 512;

// Of the maps whose robot drove nearest to where the query's did (at the
// prior) -- they saw the same place from the same spots -- the ones whose
// grids could explain the query within the prior window best (the search's
// own bound at its coarsest level), each with the pose the prior implies in
// it. *match: the window that covers the prior.
std::vector<Candidate> NearestCandidates(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options,
                                         const Prior& prior, const std::vector<MapSource::Anchored>& nearest,
                                         size_t maps, ScanMatchOptions* match) {
  *match = PriorWindow(prior, options);
  struct Bounded {
    double bound;
    double window_deg;  // its guess's heading window
    Candidate candidate;
  };
  std::vector<Bounded> bounded;
  for (const MapSource::Anchored& a : nearest) {
    std::shared_ptr<const PreparedMap> db = source.Prepared(a.map_id);
    if (!db) continue;
    double needed_deg = 0.0;
    const Pose2 guess = PriorGuess(query, *db, a.pose, prior, match->window_deg, &needed_deg);
    const double bound = FitNear(query, *db, guess, match->window_m, kBoundBlockM);
    bounded.push_back({bound, needed_deg, Candidate{a.map_id, {guess}, bound, bounded.size()}});
  }
  std::stable_sort(bounded.begin(), bounded.end(), [](const Bounded& x, const Bounded& y) { return x.bound > y.bound; });
  // The window covers the maps kept, not those passed over.
  double window_deg = match->window_deg;
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < bounded.size() && i < maps; ++i) {
    candidates.push_back(bounded[i].candidate);
    window_deg = std::max(window_deg, bounded[i].window_deg);
  }
  match->window_deg = window_deg;
  return candidates;
}

// `match` with the zone around `pose` (self_rival_radius_m of the query's
// centroid and self_rival_angle_deg) left out of the search.
ScanMatchOptions Excluding(const ScanMatchOptions& match, const LocalQuery& query, const Pose2& pose,
                           const LocalizeOptions& options) {
  ScanMatchOptions excluding = match;
  excluding.correlative.exclude_centroid = TransformPoint(pose, query.match.centroid);
  excluding.correlative.exclude_theta = pose.theta;
  excluding.correlative.exclude_radius_m = options.self_rival_radius_m;
  excluding.correlative.exclude_angle_rad = options.self_rival_angle_deg * M_PI / 180;
  return excluding;
}

// Each verified map's best pose elsewhere in its window (from the same
// guesses): within a prior's metres a corridor shifted along itself can
// out-score the true pose on the search's own measure but not on the
// verification's (lmd-eval prior-misses: 121 of 272 misses). The caller
// keeps each map's better hit.
std::vector<LocalizedHit> NextBestPoses(const LocalQuery& query, const std::vector<Candidate>& candidates,
                                        const std::vector<LocalizedHit>& verified, const ScanMatchOptions& match,
                                        const LocalizeOptions& options, LocalizeStats* stats) {
  const auto t = std::chrono::steady_clock::now();
  std::vector<LocalizedHit> out;
  for (const LocalizedHit& best : verified) {
    const auto c = std::find_if(candidates.begin(), candidates.end(),
                                [&](const Candidate& k) { return k.map_id == best.map_id; });
    if (c == candidates.end() || !best.db) continue;
    const ScanMatch next =
        MatchLocalMaps(query.match, *best.db, c->guesses, Excluding(match, query, best.pose, options));
    ++stats->maps_matched;
    ++stats->second_poses;
    if (next.score <= 0) continue;
    LocalizedHit hit = Scored(query, *best.db, next, options);
    hit.map_id = best.map_id;
    hit.db = best.db;
    out.push_back(std::move(hit));
  }
  stats->verify_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  return out;
}

// Each of the maps nearest the prior that does not fit (below min_score)
// at the turn its compass gave, searched again from the prior's own heading
// over the prior's whole heading range. The entropy compass gives a map's
// heading to a fraction of a degree where walls meet at right angles, and
// one tens of degrees off where they do not (a campus' paths and lawns):
// lmd-eval prior-misses found the compass more than 3 deg off for 8 % of
// the pairs of maps of one place on frcampus and 20 % on csail, and 0-0.4 %
// on aces, fr079, mit and orebro. The caller keeps each map's better hit.
std::vector<LocalizedHit> CompassFreePoses(const LocalQuery& query, const MapSource& source, const Prior& prior,
                                           const std::vector<Candidate>& nearest,
                                           const std::vector<LocalizedHit>& verified, const ScanMatchOptions& match,
                                           const LocalizeOptions& options, LocalizeStats* stats) {
  const auto t = std::chrono::steady_clock::now();
  ScanMatchOptions wide = match;
  wide.window_deg = options.match.window_deg + 2 * prior.heading_sigma_rad * 180 / M_PI;
  // A search over tens of degrees is costly where nothing fits: there the
  // search's own floor ends it early (prior_weak_fits lifts it at the turn).
  wide.correlative.min_score = options.match.correlative.min_score;
  std::vector<LocalizedHit> out;
  for (const Candidate& c : nearest) {
    const LocalizedHit* best = nullptr;
    for (const LocalizedHit& h : verified) {
      if (h.map_id == c.map_id && h.db && (!best || h.score > best->score)) best = &h;
    }
    const std::optional<Pose2> anchor = source.AnchorOf(c.map_id);
    if (!best || best->score >= options.confidence.min_score || !anchor) continue;
    double window_deg = 0.0;
    PriorGuess(query, *best->db, *anchor, prior, match.window_deg, &window_deg);
    if (window_deg >= wide.window_deg) continue;  // the prior's own heading range was searched
    const ScanMatch m = MatchLocalMaps(query.match, *best->db, {Compose(Inverse(*anchor), prior.pose)}, wide);
    ++stats->maps_matched;
    LocalizedHit again = Scored(query, *best->db, m, options);
    if (again.score <= best->score) continue;
    again.map_id = c.map_id;
    again.db = best->db;
    out.push_back(std::move(again));
  }
  stats->verify_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  return out;
}

// The best-bounded prior_maps of the maps near a prior (`near`) not
// verified yet (LocalizeOptions::prior_any_near_maps).
std::vector<LocalizedHit> VerifyAnyNear(const LocalQuery& query, const MapSource& source,
                                        const LocalizeOptions& options, const Prior& prior,
                                        const std::vector<MapSource::Anchored>& near,
                                        const std::vector<LocalizedHit>& verified, LocalizeStats* stats) {
  std::unordered_set<uint64_t> done;
  for (const LocalizedHit& h : verified) done.insert(h.map_id);
  std::vector<MapSource::Anchored> rest;
  for (const MapSource::Anchored& a : near) {
    if (done.count(a.map_id) == 0) rest.push_back(a);
  }
  if (rest.size() > options.prior_any_near_max_maps) {  // the newest: they show the place as it is now
    std::sort(rest.begin(), rest.end(),
              [](const MapSource::Anchored& a, const MapSource::Anchored& b) { return a.map_id > b.map_id; });
    rest.resize(options.prior_any_near_max_maps);
  }
  ScanMatchOptions match;
  const std::vector<Candidate> candidates =
      NearestCandidates(query, source, options, prior, rest, options.prior_maps, &match);
  return VerifyCandidates(query, source, candidates, options, match, stats);
}

}  // namespace

ScanMatchOptions PriorWindow(const Prior& prior, const LocalizeOptions& options) {
  ScanMatchOptions match = options.match;
  match.window_m = prior.radius_m + options.prior_margin_m;
  if (options.prior_weak_fits) match.correlative.min_score = 0.0;
  return match;
}

double CompassTurn(double compass, double theta) {
  const double quarter = M_PI / 2;
  return compass + quarter * std::round(std::remainder(theta - compass, 2 * M_PI) / quarter);
}

Pose2 PriorGuess(const LocalQuery& query, const PreparedMap& db, const Pose2& anchor, const Prior& prior,
                 double window_deg, double* search_window_deg) {
  Pose2 guess = Compose(Inverse(anchor), prior.pose);
  const double turn = CompassTurn(db.heading - query.map->heading, guess.theta);
  const bool snapped =
      std::abs(std::remainder(turn - guess.theta, 2 * M_PI)) <= 2 * prior.heading_sigma_rad + window_deg * M_PI / 180;
  if (snapped) guess.theta = turn;
  *search_window_deg = snapped ? window_deg : window_deg + 2 * prior.heading_sigma_rad * 180 / M_PI;
  return guess;
}

Status ValidatePrior(const Prior& prior) {
  if (!std::isfinite(prior.pose.x) || !std::isfinite(prior.pose.y) || !std::isfinite(prior.pose.theta)) {
    return Status::InvalidArgument("the prior's pose is not finite");
  }
  if (!(prior.radius_m > 0) || prior.radius_m > 100.0) {
    return Status::InvalidArgument("the prior's radius must be in (0, 100] m, got " + std::to_string(prior.radius_m));
  }
  if (!(prior.heading_sigma_rad >= 0) || !std::isfinite(prior.heading_sigma_rad)) {
    return Status::InvalidArgument("the prior's heading uncertainty must be a finite angle >= 0");
  }
  return Status::Ok();
}

Localization LocalizeNear(const LocalQuery& query, const MapSource& source, const LocalizeOptions& given,
                          const Prior& prior, const std::function<bool(uint64_t)>& excluded,
                          const std::function<bool()>& stop, bool with_changes) {
  LocalizeOptions options = WithStop(given, stop);
  // Hits ranked by their score, without closeness (LocalizeOptions::
  // closeness_weight): the prior has ruled out the look-alikes beyond its
  // window, the maps near it show one place, and of those the one that
  // explains the most of the query gives its pose.
  options.closeness_weight = 0;
  Localization out;
  // Where the query's points can lie in the collection's frame.
  const double reach = QueryReach(query);
  // Where its robot drove, at the prior.
  std::vector<Point2> path;
  for (const Pose2& p : query.source.trajectory) path.push_back(TransformPoint(prior.pose, {p.x, p.y}));
  if (path.empty()) path.push_back({prior.pose.x, prior.pose.y});
  const double max_off_m = prior.radius_m + options.prior_margin_m;
  const double max_turn = 2 * prior.heading_sigma_rad + options.match.window_deg * M_PI / 180;
  auto inside = [&](uint64_t map_id, const Pose2& in_map) {
    const std::optional<Pose2> anchor = source.AnchorOf(map_id);
    if (!anchor) return false;
    const Pose2 p = Compose(*anchor, in_map);
    return std::hypot(p.x - prior.pose.x, p.y - prior.pose.y) <= max_off_m &&
           std::abs(std::remainder(p.theta - prior.pose.theta, 2 * M_PI)) <= max_turn;
  };
  // Two sets of candidates, verified each in its own window. The nearest
  // maps at the pose the prior implies: right when the prior is close and
  // the first stage is not (a view its features do not tell apart). And the
  // first stage over the maps near the prior only: it says which of them
  // show what the query shows, and where, whatever the prior's error; its
  // hypotheses that put the query outside the prior are look-alikes
  // elsewhere on the site (a map near the prior also shows places away from
  // it). A tight prior (a tracking robot's) skips the second set and has more
  // of the nearest verified (LocalizeOptions::tight_prior_radius_m).
  const bool tight = options.prior_first_stage && prior.radius_m <= options.tight_prior_radius_m &&
                     prior.heading_sigma_rad <= options.tight_prior_sigma_deg * M_PI / 180;
  const size_t maps = tight ? options.tight_prior_maps : options.prior_maps;
  const bool loose = options.prior_first_stage && !tight;  // a robot's loose prior, not a sequence's check
  ScanMatchOptions near_match;
  const std::vector<Candidate> nearest =
      NearestCandidates(query, source, options, prior,
                        source.NearestAnchored(path, prior.radius_m + reach, kBoundedPerMatched * maps, excluded),
                        maps, &near_match);
  std::vector<LocalizedHit> hits;
  auto keep_each_once = [&](std::vector<LocalizedHit>* kept) {
    // Each map once, at its better fit; none that the match moved outside the prior.
    SortHits(kept, options);
    std::unordered_set<uint64_t> seen;
    kept->erase(std::remove_if(kept->begin(), kept->end(),
                               [&](const LocalizedHit& h) { return !inside(h.map_id, h.pose) || !seen.insert(h.map_id).second; }),
                kept->end());
    SetCollectionPoses(source, kept);
  };
  LocalizeOptions judged = options;
  // Fitted to global answers; a prior rules most look-alikes out itself.
  judged.confidence.min_global_probability = 0.0;
  // Whether a robot's nearest maps already make a sure answer, judged as
  // Conclude will judge them, and how many besides the best agree and fit.
  struct NearestVerdict {
    bool sure = false;
    size_t confirming = 0;
  };
  auto judge_nearest = [&](const std::vector<LocalizedHit>& these) {
    NearestVerdict verdict;
    if (!options.prior_first_stage) return verdict;
    std::vector<LocalizedHit> kept = these;
    keep_each_once(&kept);
    std::vector<JudgedHit> as_judged = AsJudged(kept);
    // Maps that may bend more than a sure answer's promise allows cannot
    // make one, whatever their fit (Conclude adds their bends).
    verdict.sure = Judge(&as_judged, judged.confidence).sure &&
                   (!query.map || !kept.front().db ||
                    PoseKnownToPromise(BendCovariance(*query.map, *kept.front().db), options.confidence));
    for (size_t i = 1; i < as_judged.size(); ++i) {
      verdict.confirming += as_judged[i].agrees_with_best && as_judged[i].score >= options.confidence.min_score;
    }
    return verdict;
  };
  // A loose prior's nearest maps are verified best-bounded first, until
  // they make a sure answer that kConfirmingMaps confirm. Others verify all
  // and are judged once: the same stop for a tight prior cost its sure
  // answers precision (LocalizeOptions::prior_maps).
  bool nearest_sure = false;
  for (size_t i = 0; i < nearest.size(); ++i) {
    for (LocalizedHit& hit : VerifyCandidates(query, source, {nearest[i]}, options, near_match, &out.stats)) {
      hits.push_back(std::move(hit));
    }
    if (!loose && i + 1 < nearest.size()) continue;
    const NearestVerdict verdict = judge_nearest(hits);
    nearest_sure = verdict.sure;
    if (loose && verdict.sure && verdict.confirming >= kConfirmingMaps) break;
  }
  // Where they do not make it sure, each map's best pose away from the one
  // found may be what was missing (a corridor the search shifted along
  // itself). Where they do, a best shifted so is still caught as a rival:
  // Conclude searches the best map's other poses before it says sure.
  if (options.prior_second_pose && !tight && !nearest_sure) {
    for (LocalizedHit& hit : NextBestPoses(query, nearest, hits, near_match, options, &out.stats)) {
      hits.push_back(std::move(hit));
    }
    nearest_sure = judge_nearest(hits).sure;
  }
  if (options.prior_first_stage && !nearest_sure) {
    for (LocalizedHit& hit : SiteGridHits(query, source, options, prior, excluded, &out.stats)) {
      hits.push_back(std::move(hit));
    }
  }
  // The anchored maps that can overlap the prior region.
  auto anchored_near = [&] {
    return source.AnchoredNear({prior.pose.x, prior.pose.y}, prior.radius_m + reach, kStageMapsPerCell, excluded);
  };
  const std::vector<MapSource::Anchored> near =
      loose && !(options.prior_stage_when_unsure && nearest_sure) ? anchored_near() : std::vector<MapSource::Anchored>{};
  if (!near.empty()) {
    std::vector<uint64_t> ids;
    for (const MapSource::Anchored& a : near) ids.push_back(a.map_id);
    LocalizeOptions stage = options;
    stage.search.only = &ids;
    stage.search.max_hypotheses = kPriorHypotheses;
    stage.search.hypotheses_per_map = kPriorPeaksPerMap;
    stage.search.max_candidates = kPriorStageReads;
    stage.search.min_candidates_per_map = 0;  // the prior's maps are few whatever the collection holds
    stage.verify_maps = options.prior_maps;
    stage.route_same_place_m = 0;  // inside the prior every hypothesis names one place: routes alone decide
    // Retrying passed-over maps here, measured (lmd-eval served --mode prior,
    // back to back): place@1 0.975 -> 0.977 but sure and wrong 58 -> 60
    // (tuning logs 19 -> 20) at the same CPU: not kept.
    stage.passed_over_retries = 0;
    const auto t = std::chrono::steady_clock::now();
    std::vector<PlaceHypothesis> hypotheses = source.Search(query.features, stage.search, excluded, &out.stats.search);
    out.stats.search_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    hypotheses.erase(std::remove_if(hypotheses.begin(), hypotheses.end(),
                                    [&](const PlaceHypothesis& h) {
                                      return !inside(h.map_id, HypothesisPose(h, query.map->heading));
                                    }),
                     hypotheses.end());
    out.stats.hypotheses = hypotheses.size();
    ScanMatchOptions stage_match = options.match;
    stage_match.window_m += kStageSlackM;  // the first stage's translation is good to its 1 m vote cell
    for (LocalizedHit& hit : ChooseAndVerify(query, source, hypotheses, stage, stage_match, &out.stats)) {
      hits.push_back(std::move(hit));
    }
  }
  // Whether a hit within the prior fits (reaches the verdict's min_score).
  auto fits_inside = [&] {
    return std::any_of(hits.begin(), hits.end(), [&](const LocalizedHit& h) {
      return h.score >= options.confidence.min_score && inside(h.map_id, h.pose);
    });
  };
  // Where none fits, a map near the prior that none of the above verified
  // (LocalizeOptions::prior_any_near_maps). A loose prior has read those
  // maps already: with nothing fitting, its nearest maps were not sure.
  if (options.prior_any_near_maps && !tight && !fits_inside()) {
    std::vector<MapSource::Anchored> read_here;
    if (!loose) read_here = anchored_near();
    for (LocalizedHit& hit :
         VerifyAnyNear(query, source, options, prior, loose ? near : read_here, hits, &out.stats)) {
      hits.push_back(std::move(hit));
    }
  }
  // Where still none fits at the compass's turn, the compass may be what
  // failed. Served (lmd-eval served --mode prior --no-changes, back to back,
  // 2026-12-05): place@1 held out .978 -> .985, tuned on .986 -> .988, sure
  // and wrong 50 -> 48, lmdd CPU 9.4 / 42.8 -> 9.6 / 55.7 ms median / p99.
  // Loose priors only: a tight prior's heading window is a few degrees
  // (--mode tracking gained no answer), and a sequence checks many windows
  // where nothing fits (+56 % CPU, no answer gained).
  if (loose && !fits_inside()) {
    for (LocalizedHit& hit : CompassFreePoses(query, source, prior, nearest, hits, near_match, options, &out.stats)) {
      hits.push_back(std::move(hit));
    }
  }
  keep_each_once(&hits);
  const bool failed = hits.empty() || hits[0].score < options.confidence.min_score;
  // Another pose of the best map within the prior window (at its heading:
  // another turn would be outside the prior's), beyond `radius_m` of it
  // (query centroid); a match that ICP brings back within it is the same
  // optimum, not a rival.
  auto other_pose = [&](const LocalizedHit& best, double radius_m) {
    ScanMatchOptions window = options.match;
    window.window_m = max_off_m;
    ScanMatchOptions excluding = Excluding(window, query, best.pose, options);
    excluding.correlative.exclude_radius_m = radius_m;
    const ScanMatch second = MatchLocalMaps(query.match, *best.db, {best.pose}, excluding);
    const Point2 p = TransformPoint(second.pose, query.match.centroid);
    const bool back = std::hypot(p.x - excluding.correlative.exclude_centroid.x,
                                 p.y - excluding.correlative.exclude_centroid.y) <= radius_m;
    return back ? 0.0 : Scored(query, *best.db, second, options).score;
  };
  const bool closer_rival =
      loose && options.prior_near_rival_m > 0 && options.prior_near_rival_m < options.self_rival_radius_m;
  std::function<double(const LocalizedHit&)> second_pose;
  if (options.self_rival_radius_m > 0) {
    second_pose = [&](const LocalizedHit& best) {
      const double far = other_pose(best, options.self_rival_radius_m);
      return closer_rival ? std::max(far, other_pose(best, options.prior_near_rival_m)) : far;
    };
  }
  Conclude(query, judged, std::move(hits), second_pose, with_changes, &out, options.prior_changes_without_margin,
           SiteMaps{&source, &excluded});
  // The robot says its map lies within the prior's radius. The search looks
  // prior_margin_m beyond it (a match needs room to converge), but an answer
  // out there contradicts the robot: a look-alike along a corridor, or a
  // prior that understated its error; either way not sure. A sure answer may
  // be off by max_pose_spread_m (what it promises), so that much beyond the
  // radius still agrees.
  const std::optional<Pose2>& at = out.verdict.collection_pose;
  if (options.prior_first_stage && at &&
      std::hypot(at->x - prior.pose.x, at->y - prior.pose.y) > prior.radius_m + options.confidence.max_pose_spread_m) {
    out.verdict.sure = false;
    SetConfidence(&out.verdict, true, judged.confidence);
  }
  out.verdict.prior_used = true;
  out.verdict.prior_failed = failed;
  return out;
}

}  // namespace lmd
