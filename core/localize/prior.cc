#include "core/localize/prior.h"

#include <algorithm>
#include <cmath>

#include "core/align/correlative_search.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

using namespace localize_internal;

namespace {

// Maps nearest the query's path bounded per map matched.
constexpr size_t kBoundedPerMatched = 4;

}  // namespace

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

Localization LocalizeNear(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options,
                          const Prior& prior, const std::function<bool(uint64_t)>& excluded,
                          const std::function<bool()>& stop, bool with_changes) {
  Localization out;
  // Where the query's points can lie in the collection's frame.
  double reach = 0.0;
  for (const Point2& p : query.match.search_points) reach = std::max(reach, std::hypot(p.x, p.y));
  const Point2 at{prior.pose.x, prior.pose.y};
  std::vector<MapSource::Anchored> near = source.AnchoredNear(at, prior.radius_m + reach);
  near.erase(std::remove_if(near.begin(), near.end(),
                            [&](const MapSource::Anchored& a) { return excluded && excluded(a.map_id); }),
             near.end());
  // Maps whose robot drove nearest to where the query's did (at the prior)
  // first: they saw the same place from the same spots.
  std::vector<Point2> path;
  for (const Pose2& p : query.source.trajectory) path.push_back(TransformPoint(prior.pose, {p.x, p.y}));
  if (path.empty()) path.push_back(at);
  auto gap = [&](const MapSource::Anchored& a) {
    double best = 1e300;
    for (const Point2& q : path) {
      for (const Point2& p : a.path) best = std::min(best, std::hypot(p.x - q.x, p.y - q.y));
    }
    return best;
  };
  std::vector<std::pair<double, size_t>> order;
  for (size_t i = 0; i < near.size(); ++i) order.push_back({gap(near[i]), i});
  std::sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : near[a.second].map_id < near[b.second].map_id;
  });
  std::vector<MapSource::Anchored> ranked;
  for (const auto& [g, i] : order) ranked.push_back(std::move(near[i]));
  near = std::move(ranked);
  // Of the nearest, those whose grids could explain the query within the
  // window best (the search's own bound at its coarsest level) are matched.
  if (near.size() > kBoundedPerMatched * options.prior_maps) near.resize(kBoundedPerMatched * options.prior_maps);
  ScanMatchOptions match = options.match;
  match.window_m = prior.radius_m + options.prior_margin_m;
  double window_deg = match.window_deg;
  std::vector<std::pair<double, Candidate>> bounded;
  for (const MapSource::Anchored& a : near) {
    std::shared_ptr<const PreparedMap> db = source.Prepared(a.map_id);
    if (!db) continue;
    // At the turn the two compasses give (the heading is known modulo 90 deg
    // to a fraction of a degree) when it lies within the prior's heading
    // uncertainty; else across the prior's whole heading range.
    Pose2 guess = Compose(Inverse(a.pose), prior.pose);
    const double quarter = M_PI / 2;
    const double compass = db->heading - query.map->heading;
    const double snapped = compass + quarter * std::round(std::remainder(guess.theta - compass, 2 * M_PI) / quarter);
    const double off = std::abs(std::remainder(snapped - guess.theta, 2 * M_PI));
    if (off <= 2 * prior.heading_sigma_rad + match.window_deg * M_PI / 180) {
      guess.theta = snapped;
    } else {
      window_deg = std::max(window_deg, (2 * prior.heading_sigma_rad) * 180 / M_PI + match.window_deg);
    }
    SearchRegion region;
    region.theta = guess.theta;
    region.centroid_target = TransformPoint(guess, query.match.centroid);
    region.half_window_x_m = region.half_window_y_m = match.window_m;
    const double bound = CorrelativeBound(query.match.search_points, *db, region);
    bounded.push_back({bound, Candidate{a.map_id, {guess}, bound, bounded.size()}});
  }
  std::stable_sort(bounded.begin(), bounded.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < bounded.size() && i < options.prior_maps; ++i) candidates.push_back(bounded[i].second);
  match.window_deg = window_deg;
  std::vector<LocalizedHit> hits = VerifyCandidates(query, source, candidates, options, match, stop, &out.stats);
  SetCollectionPoses(source, &hits);
  const bool failed = hits.empty() || hits[0].score < options.confidence.min_score;
  // Another pose of the best map within the prior window.
  auto second_pose = [&](const LocalizedHit& best) {
    ScanMatchOptions excluding = match;
    excluding.correlative.exclude_centroid = TransformPoint(best.pose, query.match.centroid);
    excluding.correlative.exclude_theta = best.pose.theta;
    excluding.correlative.exclude_radius_m = options.self_rival_radius_m;
    excluding.correlative.exclude_angle_rad = options.self_rival_angle_deg * M_PI / 180;
    Pose2 guess = best.pose;
    for (const Candidate& c : candidates) {
      if (c.map_id == best.map_id) guess = c.guesses[0];
    }
    const ScanMatch second = MatchLocalMaps(query.match, *best.db, {guess}, excluding);
    const Point2 p = TransformPoint(second.pose, query.match.centroid);
    const bool back = std::hypot(p.x - excluding.correlative.exclude_centroid.x,
                                 p.y - excluding.correlative.exclude_centroid.y) <= options.self_rival_radius_m;
    return back ? 0.0 : Scored(query, *best.db, second, options).score;
  };
  Conclude(query, options, std::move(hits), second_pose, with_changes, &out);
  out.verdict.prior_used = true;
  out.verdict.prior_failed = failed;
  SetCollectionPoses(source, &out.hits);
  return out;
}

}  // namespace lmd
