#include "core/localize/localizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "core/align/correlative_search.h"
#include "core/align/icp.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace localize_internal {
namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

}  // namespace

double QueryReach(const LocalQuery& query) {
  double reach = 0.0;
  for (const Point2& p : query.match.search_points) reach = std::max(reach, std::hypot(p.x, p.y));
  return reach;
}

LocalizedHit Scored(const LocalQuery& query, const PreparedMap& db, const ScanMatch& m, const LocalizeOptions& options) {
  LocalizedHit hit;
  hit.pose = m.pose;
  hit.overlap = m.score;
  hit.closeness = m.closeness;
  hit.inlier_rms_m = m.inlier_rms_m;
  hit.conflict = m.conflict_fraction;
  hit.reverse_conflict =
      MeasureOverlap(db.sparse_points, *query.map, Inverse(m.pose), options.match.inlier_radius_m).conflict_fraction;
  hit.score = hit.overlap - options.conflict_weight * hit.conflict -
              options.reverse_conflict_weight * hit.reverse_conflict;
  return hit;
}

double RankFit(const LocalizedHit& hit, const LocalizeOptions& options) {
  return hit.score + options.closeness_weight * (hit.closeness - hit.overlap);
}

LocalizedHit ScoredAt(const LocalQuery& query, const PreparedMap& db, const Pose2& pose, const LocalizeOptions& options) {
  ScanMatch m;
  m.pose = pose;
  const Overlap o = MeasureOverlap(query.match.points, db, pose, options.match.inlier_radius_m);
  m.score = o.fraction, m.inlier_rms_m = o.rms_m, m.closeness = o.closeness, m.conflict_fraction = o.conflict_fraction;
  return Scored(query, db, m, options);
}

std::vector<JudgedHit> AsJudged(const std::vector<LocalizedHit>& hits) {
  std::vector<JudgedHit> judged;
  for (const LocalizedHit& h : hits) judged.push_back({h.score, h.pose, h.db.get(), false, h.collection_pose});
  return judged;
}

void SortHits(std::vector<LocalizedHit>* hits, const LocalizeOptions& options) {
  // Equal fits (a map that explains every query point, and its route
  // neighbour that does too): the one that explains them more closely first.
  std::stable_sort(hits->begin(), hits->end(), [&](const LocalizedHit& a, const LocalizedHit& b) {
    const double fit_a = RankFit(a, options), fit_b = RankFit(b, options);
    if (fit_a != fit_b) return fit_a > fit_b;
    if (a.score != b.score) return a.score > b.score;
    if (a.inlier_rms_m != b.inlier_rms_m) return a.inlier_rms_m < b.inlier_rms_m;
    return a.map_id < b.map_id;
  });
}

std::vector<LocalizedHit> VerifyCandidates(const LocalQuery& query, const MapSource& source,
                                           const std::vector<Candidate>& candidates, const LocalizeOptions& options,
                                           const ScanMatchOptions& match, LocalizeStats* stats) {
  const auto t = Clock::now();
  std::vector<LocalizedHit> hits;
  for (const Candidate& c : candidates) {
    if (StopAsked(options)) break;
    std::shared_ptr<const PreparedMap> db = source.Prepared(c.map_id);
    if (!db) continue;  // deleted meanwhile
    ScanMatch m;
    if (stats->maps_matched < options.whole_map_maps) {
      std::vector<double> thetas;
      for (const Pose2& g : c.guesses) thetas.push_back(g.theta), thetas.push_back(g.theta + M_PI);
      m = MatchLocalMapsAtTurns(query.match, *db, thetas, match);
    } else {
      m = MatchLocalMaps(query.match, *db, c.guesses, match);
    }
    ++stats->maps_matched;
    LocalizedHit hit = Scored(query, *db, m, options);
    hit.map_id = c.map_id;
    hit.votes = c.votes;
    hit.first_stage_rank = c.first_rank;
    hit.db = std::move(db);
    hits.push_back(std::move(hit));
  }
  SortHits(&hits, options);
  stats->verify_ms += MsSince(t);
  return hits;
}

std::vector<AlignedMap> PlaceMaps(const std::vector<LocalizedHit>& hits, double best_score,
                                  const LocalizeOptions& options) {
  std::vector<AlignedMap> place;
  for (const LocalizedHit& h : hits) {
    if (h.agrees_with_best && h.db && h.score >= best_score - options.confidence.agreement_window) {
      place.push_back({h.db.get(), h.pose, h.map_id});
    }
  }
  return place;
}

double PlaceFit(const LocalQuery& query, const std::vector<AlignedMap>& place, const LocalizeOptions& options) {
  const std::vector<Point2>& points = query.match.points;
  if (points.empty()) return 0.0;
  double fit = 0.0;
  for (const Point2& p : points) {
    bool explained = false, in_free_space = false;
    for (const AlignedMap& m : place) {
      const Point2 in_map = TransformPoint(m.pose, p);
      explained = NearestPoint(*m.db, in_map, options.match.inlier_radius_m) >= 0;
      if (explained) break;
      in_free_space = in_free_space || InFreeSpace(*m.db, in_map);
    }
    fit += explained ? 1.0 : in_free_space ? -options.conflict_weight : 0.0;
  }
  return fit / static_cast<double>(points.size());
}

bool PlaceClear(const LocalQuery& query, const std::vector<LocalizedHit>& hits, const Verdict& verdict,
                const std::vector<AlignedMap>& place, const LocalizeOptions& options, bool prior_place) {
  if (hits.empty()) return false;
  const double min_score = options.confidence.min_score;
  double fit = verdict.best_score;
  if (options.changes_place_fit_before_conflicts) fit = std::max(fit, hits[0].overlap);
  if (options.changes_place_fit_of_union && fit < min_score) {
    fit = std::max(fit, PlaceFit(query, place, options));
  }
  return fit >= min_score && (prior_place || verdict.best_score - verdict.rival_score >= options.confidence.min_margin);
}

std::vector<AlignedMap> WithSiteMaps(const LocalQuery& query, const LocalizedHit& best, std::vector<AlignedMap> place,
                                     const SiteMaps& site, const LocalizeOptions& options,
                                     std::vector<std::shared_ptr<const PreparedMap>>* kept) {
  if (!site.source || !site.excluded || !best.collection_pose || options.changes_site_maps == 0) return place;
  const Pose2& at = *best.collection_pose;
  std::vector<Point2> path;
  for (const Pose2& p : query.source.trajectory) path.push_back(TransformPoint(at, {p.x, p.y}));
  if (path.empty()) path.push_back({at.x, at.y});
  for (const MapSource::Anchored& a :
       site.source->NearestAnchored(path, QueryReach(query), options.changes_site_maps, *site.excluded)) {
    const bool placed =
        std::any_of(place.begin(), place.end(), [&](const AlignedMap& m) { return m.id == a.map_id; });
    if (placed) continue;
    std::shared_ptr<const PreparedMap> db = site.source->Prepared(a.map_id);
    if (!db) continue;
    place.push_back({db.get(), Compose(Inverse(a.pose), at), best.map_id});
    kept->push_back(std::move(db));
  }
  return place;
}

void Conclude(const LocalQuery& query, const LocalizeOptions& options, std::vector<LocalizedHit> hits,
              const std::function<double(const LocalizedHit& best)>& second_pose, bool with_changes,
              Localization* out, bool prior_place, const SiteMaps& site_maps) {
  auto t = Clock::now();
  if (!hits.empty() && options.refine_best) {
    LocalizedHit& best = hits[0];
    const Pose2 refined_pose = RefinePose(query.match.points, *best.db, best.pose, options.refine);
    LocalizedHit refined = ScoredAt(query, *best.db, refined_pose, options);
    if (refined.score >= best.score) {
      refined.map_id = best.map_id, refined.votes = best.votes, refined.first_stage_rank = best.first_stage_rank;
      refined.db = best.db;
      if (best.collection_pose) {  // the same anchor, the refined pose
        refined.collection_pose = Compose(Compose(*best.collection_pose, Inverse(best.pose)), refined.pose);
      }
      best = std::move(refined);
    }
  }
  std::vector<JudgedHit> judged = AsJudged(hits);
  out->verdict = Judge(&judged, options.confidence);
  // Only a sure verdict can be overturned by another pose of the best map.
  if (out->verdict.sure && second_pose) {
    const double second = second_pose(hits[0]);
    if (second > 0) out->verdict = Judge(&judged, options.confidence, second);
  }
  // An answer whose searches were given up (their stop) is never sure, nor
  // its place clear: the rivals were not all looked for. Nor one of a few
  // points (min_sure_points).
  const bool cannot_be_sure = StopAsked(options) || query.match.points.size() < options.min_sure_points;
  if (cannot_be_sure) out->verdict.sure = false;
  // Nor one whose map the votes do not single out (sure_vote_lead): a map
  // never looked at may show another place that fits as well.
  if (out->stats.unexamined_votes > 0 && !hits.empty()) {
    out->verdict.vote_lead = hits[0].votes - out->stats.unexamined_votes;
    if (options.sure_vote_lead > 0 && *out->verdict.vote_lead < options.sure_vote_lead) out->verdict.sure = false;
  }
  if (!hits.empty() && hits[0].db) {
    out->verdict.pose_covariance =
        PoseCovariance(query.match.points, *hits[0].db, hits[0].pose, options.refine, options.pose_covariance);
    if (query.map) out->verdict.pose_covariance += BendCovariance(*query.map, *hits[0].db);
  }
  // Nor one whose fit does not know its pose as closely as a sure answer
  // promises, nor one whose map does not pin it that closely.
  if (out->verdict.sure) out->verdict.sure = PoseKnownToPromise(out->verdict.pose_covariance, options.confidence);
  if (out->verdict.sure && options.confidence.min_slide_margin > 0) {
    out->verdict.slide_margin = SlideMargin(query, hits[0], options, options.confidence);
    out->verdict.sure = out->verdict.slide_margin >= options.confidence.min_slide_margin;
  }
  // Nor, in a collection with anchored maps, one whose place in the site
  // its anchored hits do not name (sure_needs_site). Where the naming hit is
  // not the best, its own map's other poses are look-alikes too (a map may
  // show two identical rooms); the best's were searched above.
  const int named = SiteNamingHit(judged);
  if (out->verdict.sure && options.sure_needs_site && site_maps.source != nullptr && site_maps.source->HasAnchors()) {
    out->verdict.sure = SitePlaceClear(judged, named, 0.0, options.confidence);
    if (out->verdict.sure && named > 0 && second_pose) {  // the search only where it could matter
      const double other = second_pose(hits[static_cast<size_t>(named)]);
      out->verdict.sure = SitePlaceClear(judged, named, other, options.confidence);
    }
  }
  SetConfidence(&out->verdict, !hits.empty(), options.confidence);
  for (size_t i = 0; i < hits.size(); ++i) hits[i].agrees_with_best = judged[i].agrees_with_best;
  out->stats.verdict_ms += MsSince(t);

  // A change mask needs the place, not the pose to 0.2 m that a sure answer
  // promises: masks also where the place is clear (PlaceClear), though the
  // calibrated confidence or the maps' pose spread keep the answer unsure.
  const Verdict& v = out->verdict;
  const std::vector<AlignedMap> place =
      with_changes ? PlaceMaps(hits, v.best_score, options) : std::vector<AlignedMap>{};
  const bool place_clear = with_changes && options.changes_where_place_clear && !cannot_be_sure && !v.sure &&
                           PlaceClear(query, hits, v, place, options, prior_place);
  if (with_changes && (v.sure || place_clear)) {
    t = Clock::now();
    std::vector<std::shared_ptr<const PreparedMap>> kept;
    out->changes = GeometricChanges(query.source.points, query.source.trajectory, query.source.scans,
                                    WithSiteMaps(query, hits[0], place, site_maps, options, &kept), options.changes);
    out->stats.changes_ms += MsSince(t);
  }
  const std::optional<Pose2> site = options.fuse_site_pose ? FusedSitePose(hits, options.confidence) : std::nullopt;
  if (named >= 0 && options.top_k > 0) {  // (the best agrees with itself; top_k 0 returns no hit)
    out->verdict.collection_pose = site ? site : hits[static_cast<size_t>(named)].collection_pose;
    out->verdict.collection_pose_hit = static_cast<size_t>(named);
  }
  if (hits.size() > options.top_k) {
    // The hit that gives the site pose is returned, after the top_k where
    // it ranks lower: a robot asking for few hits still learns its place.
    if (out->verdict.collection_pose && out->verdict.collection_pose_hit >= options.top_k) {
      std::swap(hits[options.top_k], hits[out->verdict.collection_pose_hit]);
      out->verdict.collection_pose_hit = options.top_k;
      hits.resize(options.top_k + 1);
    } else {
      hits.resize(options.top_k);
    }
  }
  if (!hits.empty() && hits[0].db) {
    const LocalizedHit& best = hits[0];
    if (out->verdict.collection_pose) {
      // The hit's frame turned into the collection's.
      const double turn = out->verdict.collection_pose->theta - best.pose.theta;
      Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
      rotation.topLeftCorner<2, 2>() << std::cos(turn), -std::sin(turn), std::sin(turn), std::cos(turn);
      out->verdict.collection_pose_covariance = rotation * out->verdict.pose_covariance * rotation.transpose();
    }
  }
  out->hits = std::move(hits);
}

namespace {

// A match of the best map at another pose ends with a verification score
// of at most 1 / kRivalSearchShare times its search score, so a search
// score below kRivalSearchShare times the highest harmless rival cannot
// make a rival that changes the verdict. Measured (lmd-eval retrieval
// --methods best, 1,526 second poses): verification / search score at most
// 1.31 (median 0.68); 0.75 is 1 / 1.33.
constexpr double kRivalSearchShare = 0.75;

}  // namespace

double OtherPoseScore(const LocalQuery& query, const LocalizedHit& best, const LocalizeOptions& options,
                      const ConfidenceOptions& verdict) {
  // The search's floor: its bound then prunes most of the map.
  ScanMatchOptions match = options.match;
  match.correlative.min_score =
      std::max(match.correlative.min_score, kRivalSearchShare * HighestHarmlessRival(best.score, verdict));
  const ScanMatch second = SecondBestMatch(query.match, *best.db, best.pose, options.self_rival_radius_m,
                                           options.self_rival_angle_deg, match);
  return second.score > 0 ? Scored(query, *best.db, second, options).score : 0.0;
}

std::function<double(const LocalizedHit& best)> OtherPoseRival(const LocalQuery& query, const LocalizeOptions& options,
                                                               const ConfidenceOptions& verdict) {
  if (options.self_rival_radius_m <= 0) return {};
  return [&query, &options, &verdict](const LocalizedHit& best) { return OtherPoseScore(query, best, options, verdict); };
}

double SlideMargin(const LocalQuery& query, const LocalizedHit& best, const LocalizeOptions& options,
                   const ConfidenceOptions& verdict) {
  const std::vector<Point2>& points = query.match.points;
  if (points.empty() || !best.db) return 0.0;
  const PreparedMap& db = *best.db;
  const double close_m = options.match.inlier_radius_m / 3, slide_m = verdict.max_pose_spread_m;
  // The query's points in the map's frame; a point farther than close_m +
  // slide_m from the map's cannot come within close_m by a slide, so only
  // the others are slid (all of them where the buckets do not reach that far).
  const double reach_m = close_m + slide_m;
  const bool prune = reach_m <= db.options.neighbour_cell_m;
  const double c = std::cos(best.pose.theta), s = std::sin(best.pose.theta);
  std::vector<Point2> near;
  size_t close = 0;
  for (const Point2& p : points) {
    const Point2 q{best.pose.x + c * p.x - s * p.y, best.pose.y + s * p.x + c * p.y};
    double d2 = 0.0;
    const bool within = NearestPoint(db, q, prune ? reach_m : close_m, &d2) >= 0;
    if (within && d2 <= close_m * close_m) ++close;
    if (within || !prune) near.push_back(q);
  }
  size_t kept = 0;
  for (int k = 0; k < 8; ++k) {
    const double dx = slide_m * std::cos(k * M_PI / 4), dy = slide_m * std::sin(k * M_PI / 4);
    size_t stays = 0;
    for (const Point2& q : near) stays += NearestPoint(db, {q.x + dx, q.y + dy}, close_m) >= 0;
    kept = std::max(kept, stays);
  }
  return (static_cast<double>(close) - static_cast<double>(kept)) / static_cast<double>(points.size());
}

std::optional<Pose2> FusedSitePose(const std::vector<LocalizedHit>& hits, const ConfidenceOptions& options) {
  if (hits.empty() || !hits[0].collection_pose) return std::nullopt;
  const Pose2& best = *hits[0].collection_pose;
  std::vector<Pose2> offsets;  // from the best's pose, headings wrapped around it
  for (size_t i = 0; i < hits.size(); ++i) {
    const LocalizedHit& h = hits[i];
    if (!h.collection_pose || !h.agrees_with_best || (i > 0 && h.score < options.min_score)) continue;
    offsets.push_back({h.collection_pose->x - best.x, h.collection_pose->y - best.y,
                       std::remainder(h.collection_pose->theta - best.theta, 2 * M_PI)});
  }
  if (offsets.size() < 3) return std::nullopt;
  const Pose2 mid = ComponentMedian(offsets);
  Pose2 sum{0, 0, 0};
  size_t kept = 0;
  for (const Pose2& o : offsets) {
    if (std::hypot(o.x - mid.x, o.y - mid.y) > options.max_pose_spread_m ||
        std::abs(o.theta - mid.theta) > options.max_pose_spread_deg * M_PI / 180) {
      continue;
    }
    sum.x += o.x, sum.y += o.y, sum.theta += o.theta;
    ++kept;
  }
  if (kept < 3) return std::nullopt;
  const double n = static_cast<double>(kept);
  return Pose2{best.x + sum.x / n, best.y + sum.y / n, std::remainder(best.theta + sum.theta / n, 2 * M_PI)};
}

void SetCollectionPoses(const MapSource& source, std::vector<LocalizedHit>* hits) {
  for (LocalizedHit& h : *hits) {
    if (const std::optional<Pose2> anchor = source.AnchorOf(h.map_id)) h.collection_pose = Compose(*anchor, h.pose);
  }
}

double FitNear(const LocalQuery& query, const PreparedMap& db, const Pose2& guess, double window_m, double block_m) {
  SearchRegion region;
  region.theta = guess.theta;
  region.centroid_target = TransformPoint(guess, query.match.centroid);
  region.half_window_x_m = region.half_window_y_m = window_m;
  return CorrelativeBound(query.match.search_points, db, region, block_m);
}

void RankByFit(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options, size_t max_maps,
               double block_m, std::vector<PlaceHypothesis>* hypotheses, std::unordered_set<uint64_t>* read) {
  std::unordered_map<uint64_t, std::shared_ptr<const PreparedMap>> maps;  // each read once
  std::vector<std::pair<double, PlaceHypothesis>> ranked;
  for (const PlaceHypothesis& h : *hypotheses) {
    auto it = maps.find(h.map_id);
    if (it == maps.end()) {
      if (maps.size() >= max_maps) break;
      it = maps.emplace(h.map_id, source.SearchGrid(h.map_id)).first;
    }
    const double fit =
        it->second ? FitNear(query, *it->second, HypothesisPose(h, query.map->heading), options.match.window_m, block_m)
                   : 0.0;
    ranked.push_back({fit, h});
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t i = 0; i < ranked.size(); ++i) (*hypotheses)[i] = std::move(ranked[i].second);
  if (read) {
    for (const auto& [id, grid] : maps) read->insert(id);
  }
}

namespace {

// Where `guess` puts the query in the site, for a map anchored at `anchor`.
Point2 SitePoint(const Pose2& anchor, const Pose2& guess) {
  const Pose2 site = Compose(anchor, guess);
  return {site.x, site.y};
}

// Where maps without anchors are among the candidates: anchored maps of
// `pool` neither chosen nor passed over (`seen`), best-voted first, until
// options.verify_anchored_maps of the candidates are anchored. A map joins
// at the first of its hypotheses that puts the query at a place in the
// site (route_same_place_m) no anchored candidate puts it yet, with that
// and its later hypotheses in `pool` as guesses: identical rooms are told
// apart only by anchored maps of each, and a place many maps show would
// otherwise take every slot.
void AddAnchoredCandidates(const LocalQuery& query, const MapSource& source, const std::vector<PlaceHypothesis>& pool,
                           const LocalizeOptions& options, const std::unordered_map<uint64_t, size_t>& seen,
                           std::vector<Candidate>* candidates) {
  if (options.verify_anchored_maps == 0 || !source.HasAnchors()) return;
  size_t anchored = 0;
  std::vector<Point2> places;  // where the anchored candidates' guesses put the query in the site
  for (const Candidate& c : *candidates) {
    const std::optional<Pose2> anchor = source.AnchorOf(c.map_id);
    if (!anchor) continue;
    ++anchored;
    for (const Pose2& g : c.guesses) places.push_back(SitePoint(*anchor, g));
  }
  if (anchored == candidates->size()) return;  // no map without an anchor crowded the choice
  auto placed = [&](const Point2& p) {
    return std::any_of(places.begin(), places.end(), [&](const Point2& q) {
      return std::hypot(p.x - q.x, p.y - q.y) <= options.route_same_place_m;
    });
  };
  std::unordered_map<uint64_t, size_t> added;  // map id -> candidate index
  for (size_t r = 0; r < pool.size(); ++r) {
    const PlaceHypothesis& h = pool[r];
    const Pose2 guess = HypothesisPose(h, query.map->heading);
    if (auto it = added.find(h.map_id); it != added.end()) {
      (*candidates)[it->second].guesses.push_back(guess);
      continue;
    }
    if (anchored >= options.verify_anchored_maps || seen.count(h.map_id) > 0) continue;
    const std::optional<Pose2> anchor = source.AnchorOf(h.map_id);
    if (!anchor) continue;
    const Point2 at = SitePoint(*anchor, guess);
    if (placed(at)) continue;
    places.push_back(at);
    added.emplace(h.map_id, candidates->size());
    candidates->push_back({h.map_id, {guess}, h.votes, r});
    ++anchored;
  }
}

}  // namespace

std::vector<Candidate> ChooseCandidates(const LocalQuery& query, const MapSource& source,
                                        const std::vector<PlaceHypothesis>& hypotheses, const LocalizeOptions& options,
                                        std::vector<PassedOver>* passed,
                                        const std::vector<PlaceHypothesis>* anchored_pool) {
  std::vector<Candidate> candidates;
  struct Chosen {
    MapSource::Route route;
    std::optional<Pose2> anchor;
    size_t candidate;
  };
  std::vector<Chosen> chosen;
  std::unordered_map<uint64_t, size_t> at;  // map id -> candidate index; kPassed: passed over
  std::unordered_map<uint64_t, size_t> passed_at;  // map id -> index in *passed
  constexpr size_t kPassed = static_cast<size_t>(-1);
  // Where a chosen map's guesses put the query on the site: a route
  // neighbour anchored too repeats it only when it puts the query there as well.
  auto same_place = [&](const Chosen& c, const Pose2& site) {
    for (const Pose2& g : candidates[c.candidate].guesses) {
      const Pose2 other = Compose(*c.anchor, g);
      if (std::hypot(other.x - site.x, other.y - site.y) <= options.route_same_place_m) return true;
    }
    return false;
  };
  for (size_t r = 0; r < hypotheses.size(); ++r) {
    const PlaceHypothesis& h = hypotheses[r];
    const Pose2 guess = HypothesisPose(h, query.map->heading);
    auto it = at.find(h.map_id);
    if (it == at.end()) {
      if (candidates.size() >= options.verify_maps) continue;
      MapSource::Route route;
      const bool known = options.maps_per_route_window > 0 && source.RouteOf(h.map_id, &route);
      const std::optional<Pose2> anchor = known ? source.AnchorOf(h.map_id) : std::nullopt;
      std::vector<uint64_t> near;
      for (const Chosen& c : chosen) {
        const uint64_t gap =
            c.route.sequence > route.sequence ? c.route.sequence - route.sequence : route.sequence - c.route.sequence;
        if (!known || c.route.robot != route.robot || gap > options.route_window) continue;
        if (options.route_same_place_m <= 0 || !anchor || !c.anchor || same_place(c, Compose(*anchor, guess))) {
          near.push_back(candidates[c.candidate].map_id);
        }
      }
      if (known && near.size() >= options.maps_per_route_window) {
        at.emplace(h.map_id, kPassed);
        if (passed) {
          passed_at.emplace(h.map_id, passed->size());
          passed->push_back({{h.map_id, {guess}, h.votes, r}, std::move(near)});
        }
        continue;
      }
      it = at.emplace(h.map_id, candidates.size()).first;
      if (known) chosen.push_back({route, anchor, candidates.size()});
      candidates.push_back({h.map_id, {}, h.votes, r});
    }
    if (it->second != kPassed) {
      candidates[it->second].guesses.push_back(guess);
    } else if (passed) {
      (*passed)[passed_at.at(h.map_id)].candidate.guesses.push_back(guess);
    }
  }
  AddAnchoredCandidates(query, source, anchored_pool ? *anchored_pool : hypotheses, options, at, &candidates);
  return candidates;
}

std::vector<Candidate> PassedOverFailedFits(const std::vector<PassedOver>& passed,
                                            const std::vector<LocalizedHit>& hits, const LocalizeOptions& options) {
  std::unordered_map<uint64_t, double> score_of;
  for (const LocalizedHit& h : hits) score_of[h.map_id] = h.score;
  std::vector<Candidate> retried;
  for (const PassedOver& p : passed) {
    if (retried.size() >= options.passed_over_retries) break;
    const bool failed = std::all_of(p.for_maps.begin(), p.for_maps.end(), [&](uint64_t id) {
      const auto it = score_of.find(id);
      return it == score_of.end() || it->second < options.confidence.min_score;
    });
    if (failed) retried.push_back(p.candidate);
  }
  return retried;
}

std::vector<LocalizedHit> ChooseAndVerify(const LocalQuery& query, const MapSource& source,
                                          const std::vector<PlaceHypothesis>& hypotheses,
                                          const LocalizeOptions& options, const ScanMatchOptions& match,
                                          LocalizeStats* stats, std::vector<Candidate>* verified,
                                          const std::vector<PlaceHypothesis>* anchored_pool) {
  std::vector<PassedOver> passed;
  std::vector<Candidate> candidates = ChooseCandidates(query, source, hypotheses, options, &passed, anchored_pool);
  const size_t matched_before = stats->maps_matched;
  std::vector<LocalizedHit> hits = VerifyCandidates(query, source, candidates, options, match, stats);
  const bool stopped = stats->maps_matched - matched_before < candidates.size();  // (or maps deleted meanwhile)
  std::vector<Candidate> retried = stopped ? std::vector<Candidate>{} : PassedOverFailedFits(passed, hits, options);
  if (!retried.empty()) {
    for (LocalizedHit& hit : VerifyCandidates(query, source, retried, options, match, stats)) {
      hits.push_back(std::move(hit));
    }
    SortHits(&hits, options);
  }
  if (verified) {
    *verified = std::move(candidates);
    for (Candidate& c : retried) verified->push_back(std::move(c));
  }
  return hits;
}

namespace {

// The second round (LocalizeOptions::second_round_hypotheses): the maps
// among `hypotheses` not in `verified`, all put in order of fit from
// coarser blocks, then verified as the first round's are; `verified` gains
// them.
std::vector<LocalizedHit> VerifySecondRound(const LocalQuery& query, const MapSource& source,
                                            const std::vector<PlaceHypothesis>& hypotheses,
                                            const LocalizeOptions& options, LocalizeStats* stats,
                                            std::vector<Candidate>* verified) {
  const auto t = Clock::now();
  std::unordered_set<uint64_t> done;
  for (const Candidate& c : *verified) done.insert(c.map_id);
  std::vector<PlaceHypothesis> second;
  for (const PlaceHypothesis& h : hypotheses) {
    if (done.count(h.map_id) == 0) second.push_back(h);
  }
  RankByFit(query, source, options, second.size(), options.second_round_block_m, &second);
  stats->search_ms += MsSince(t);
  std::vector<Candidate> chosen;
  std::vector<LocalizedHit> hits = ChooseAndVerify(query, source, second, options, options.match, stats, &chosen);
  for (Candidate& c : chosen) verified->push_back(std::move(c));
  return hits;
}

// Each hit's votes made those of its map's most voted hypothesis (`all`
// comes best first, by votes).
void SetMapVotes(const std::vector<PlaceHypothesis>& all, std::vector<LocalizedHit>* hits) {
  std::unordered_map<uint64_t, double> most;  // map id -> its first, most voted, hypothesis's votes
  for (const PlaceHypothesis& h : all) most.emplace(h.map_id, h.votes);
  for (LocalizedHit& hit : *hits) {
    const auto it = most.find(hit.map_id);
    if (it != most.end()) hit.votes = it->second;
  }
}

// The most votes of a map in `all` not `looked_at`. A search that returned
// its `max_hypotheses` may have cut maps with as many votes as its last.
double UnexaminedVotes(const std::vector<PlaceHypothesis>& all, size_t max_hypotheses,
                       const std::unordered_set<uint64_t>& looked_at) {
  for (const PlaceHypothesis& h : all) {
    if (!looked_at.count(h.map_id)) return h.votes;
  }
  return all.size() >= max_hypotheses && !all.empty() ? all.back().votes : 0.0;
}

}  // namespace

std::vector<LocalizedHit> SearchAndVerify(const LocalQuery& query, const MapSource& source,
                                          const LocalizeOptions& options, const std::function<bool(uint64_t)>& excluded,
                                          LocalizeStats* stats, SearchTrace* trace) {
  const auto t = Clock::now();
  // One search serves both rounds: its hypotheses come best first, so the
  // first max_hypotheses are those a search for only them returns.
  PlaceSearchOptions search = options.search;
  search.max_hypotheses = std::max(search.max_hypotheses, options.second_round_hypotheses);
  std::vector<PlaceHypothesis> all = source.Search(query.features, search, excluded, &stats->search);
  const auto first_end = all.begin() + static_cast<std::ptrdiff_t>(std::min(all.size(), options.search.max_hypotheses));
  std::vector<PlaceHypothesis> first(all.begin(), first_end);
  stats->hypotheses = first.size();
  std::unordered_set<uint64_t> looked_at;  // fit ranked or verified
  if (options.fit_rank_maps > 0) {
    RankByFit(query, source, options, options.fit_rank_maps, options.fit_rank_block_m, &first, &looked_at);
  }
  stats->search_ms += MsSince(t);
  std::vector<Candidate> verified;
  std::vector<LocalizedHit> hits =
      ChooseAndVerify(query, source, first, options, options.match, stats, &verified, /*anchored_pool=*/&all);
  const bool fits = !hits.empty() && hits[0].score >= options.confidence.min_score;
  const bool second_round = options.second_round_hypotheses > 0 && !fits && !StopAsked(options);
  if (second_round) {
    stats->hypotheses = all.size();
    for (LocalizedHit& hit : VerifySecondRound(query, source, all, options, stats, &verified)) {
      hits.push_back(std::move(hit));
    }
    SortHits(&hits, options);
  }
  for (const Candidate& c : verified) looked_at.insert(c.map_id);
  if (second_round) {
    for (const PlaceHypothesis& h : all) looked_at.insert(h.map_id);  // the second round fit ranks them all
  }
  SetMapVotes(all, &hits);
  stats->unexamined_votes = UnexaminedVotes(all, search.max_hypotheses, looked_at);
  if (trace) {
    trace->hypotheses = second_round ? std::move(all) : std::move(first);
    trace->verified = std::move(verified);
  }
  return hits;
}

LocalizeOptions WithStop(const LocalizeOptions& options, const std::function<bool()>& stop) {
  LocalizeOptions stopping = options;
  stopping.match.correlative.stop = stop;
  return stopping;
}

bool StopAsked(const LocalizeOptions& options) {
  const std::function<bool()>& stop = options.match.correlative.stop;
  return stop && stop();
}

}  // namespace localize_internal

using namespace localize_internal;

PreparedPlace PreparePlace(const LocalMap& map, const LocalizeOptions& options) {
  PreparedPlace p;
  p.map = std::make_shared<const PreparedMap>(PrepareMap(map, options.match.map));
  p.features = DescribePlace(p.map->points, p.map->heading, options.features);
  return p;
}

LocalQuery PrepareLocalQuery(LocalMap map, const LocalizeOptions& options, const PreparedPlace* prepared) {
  LocalQuery q;
  PreparedPlace place = prepared ? *prepared : PreparePlace(map, options);
  q.map = std::move(place.map);
  q.features = std::move(place.features);
  q.match = PrepareQuery(map, options.match, q.map->heading);
  q.source = std::move(map);
  return q;
}

Localization Localize(const LocalQuery& query, const MapSource& source, const LocalizeOptions& given,
                      const std::function<bool(uint64_t)>& excluded, const std::function<bool()>& stop,
                      bool with_changes) {
  const LocalizeOptions options = WithStop(given, stop);
  Localization out;
  std::vector<LocalizedHit> hits = SearchAndVerify(query, source, options, excluded, &out.stats);
  SetCollectionPoses(source, &hits);
  Conclude(query, options, std::move(hits), OtherPoseRival(query, options, options.confidence), with_changes, &out,
           /*prior_place=*/false, SiteMaps{&source, &excluded});
  return out;
}

}  // namespace lmd
