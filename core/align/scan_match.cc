#include "core/align/scan_match.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/local_map_builder.h"
#include "core/viewpoint/orientation.h"

namespace lmd {
namespace {

// Query points kept one per cell of `cell_m` (0: all).
std::vector<Point2> Subsample(const std::vector<Point2>& points, double cell_m) {
  return cell_m > 0.0 ? DeduplicatePoints(points, cell_m) : points;
}

Point2 Apply(const Pose2& pose, const Point2& p) {
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  return {pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
}

// Correlative search over `regions`, ICP, score. region_guess maps a region to its guess index.
ScanMatch Match(const PreparedQuery& query, const PreparedMap& db, const std::vector<SearchRegion>& regions,
                const std::vector<int>& region_guess, const ScanMatchOptions& options) {
  ScanMatch m;
  const CorrelativeResult coarse = CorrelativeSearch(query.search_points, db, regions, options.correlative);
  m.pose = coarse.pose;
  m.search_score = coarse.score;
  m.search_evaluations = coarse.evaluations;
  m.guess = coarse.region < region_guess.size() ? region_guess[coarse.region] : -1;
  if (!coarse.found) return m;
  m.pose = RefinePose(query.icp_points, db, coarse.pose, options.icp);
  Overlap o = MeasureOverlap(query.points, db, m.pose, options.inlier_radius_m);
  // ICP can slide off a poor lattice pose: below recheck_below the lattice
  // pose is kept if it overlaps more. Above, the refined pose stands.
  if (o.fraction < options.recheck_below) {
    const Overlap lattice = MeasureOverlap(query.points, db, coarse.pose, options.inlier_radius_m);
    if (lattice.fraction > o.fraction) o = lattice, m.pose = coarse.pose;
  }
  m.score = o.fraction;
  m.inlier_rms_m = o.rms_m;
  m.closeness = o.closeness;
  m.inliers = o.inliers;
  m.conflict_fraction = o.conflict_fraction;
  return m;
}

bool SameRegion(const SearchRegion& a, const SearchRegion& b) {
  return std::abs(std::remainder(a.theta - b.theta, 2.0 * M_PI)) < 1e-3 &&
         std::hypot(a.centroid_target.x - b.centroid_target.x, a.centroid_target.y - b.centroid_target.y) < 0.05;
}

bool Matchable(const PreparedQuery& query, const PreparedMap& db, const ScanMatchOptions& options) {
  const size_t min_points = std::max<size_t>(1, options.min_points);
  return query.points.size() >= min_points && db.points.size() >= min_points;
}

}  // namespace

PreparedQuery PrepareQuery(const LocalMap& query, const ScanMatchOptions& options,
                           std::optional<double> known_heading) {
  PreparedQuery q;
  q.points.reserve(query.points.size());
  for (const Point2& p : query.points) {
    if (std::isfinite(p.x) && std::isfinite(p.y)) q.points.push_back(p);
  }
  q.search_points = Subsample(q.points, options.search_cell_m);
  q.icp_points = Subsample(q.points, options.icp_cell_m);
  for (const Point2& p : q.search_points) {
    q.centroid.x += p.x;
    q.centroid.y += p.y;
  }
  if (!q.search_points.empty()) {
    q.centroid.x /= q.search_points.size();
    q.centroid.y /= q.search_points.size();
  }
  q.heading = known_heading ? *known_heading : EstimateDominantOrientation(q.points, options.map.orientation);
  return q;
}

ScanMatch MatchLocalMaps(const PreparedQuery& query, const PreparedMap& db, const std::vector<Pose2>& guesses,
                         const ScanMatchOptions& options) {
  if (guesses.empty()) return MatchLocalMapsGlobal(query, db, options);
  std::vector<SearchRegion> regions;
  std::vector<int> region_guess;
  const int turns = options.quarter_turns ? 4 : 1;
  for (size_t g = 0; g < guesses.size(); ++g) {
    const Point2 target = Apply(guesses[g], query.centroid);
    for (int k = 0; k < turns; ++k) {
      SearchRegion r;
      r.theta = guesses[g].theta + k * (M_PI / 2);
      r.half_window_rad = options.window_deg * M_PI / 180.0;
      r.centroid_target = target;
      r.half_window_x_m = r.half_window_y_m = options.window_m;
      bool duplicate = false;
      for (const SearchRegion& other : regions) duplicate = duplicate || SameRegion(r, other);
      if (duplicate) continue;
      regions.push_back(r);
      region_guess.push_back(static_cast<int>(g));
    }
  }
  ScanMatch m;
  if (Matchable(query, db, options)) m = Match(query, db, regions, region_guess, options);
  if (m.score == 0.0 && m.search_score == 0.0) {
    m.pose = guesses[0];
    m.guess = 0;
  }
  return m;
}

ScanMatch MatchLocalMaps(const LocalMap& query, const LocalMap& db, const std::vector<Pose2>& guesses,
                         const ScanMatchOptions& options) {
  return MatchLocalMaps(PrepareQuery(query, options), PrepareMap(db, options.map), guesses, options);
}

ScanMatch SecondBestMatch(const PreparedQuery& query, const PreparedMap& db, const Pose2& best, double radius_m,
                          double angle_deg, const ScanMatchOptions& options) {
  ScanMatchOptions excluding = options;
  excluding.correlative.exclude_centroid = Apply(best, query.centroid);
  excluding.correlative.exclude_theta = best.theta;
  excluding.correlative.exclude_radius_m = radius_m;
  excluding.correlative.exclude_angle_rad = angle_deg * M_PI / 180.0;
  ScanMatch m = MatchLocalMapsGlobal(query, db, excluding);
  const Point2 at = Apply(m.pose, query.centroid), best_at = excluding.correlative.exclude_centroid;
  const bool back = std::hypot(at.x - best_at.x, at.y - best_at.y) <= radius_m &&
                    std::abs(std::remainder(m.pose.theta - best.theta, 2.0 * M_PI)) <= excluding.correlative.exclude_angle_rad;
  if (back) m.score = 0.0;
  return m;
}

ScanMatch MatchLocalMapsAtTurns(const PreparedQuery& query, const PreparedMap& db, const std::vector<double>& thetas,
                                const ScanMatchOptions& options) {
  ScanMatch m;
  if (!Matchable(query, db, options) || thetas.empty()) return m;
  const Point2 centre{(db.min_corner.x + db.max_corner.x) / 2, (db.min_corner.y + db.max_corner.y) / 2};
  std::vector<SearchRegion> regions;
  for (double theta : thetas) {
    SearchRegion r;
    r.theta = theta;
    r.half_window_rad = options.window_deg * M_PI / 180.0;
    r.centroid_target = centre;
    r.half_window_x_m = (db.max_corner.x - db.min_corner.x) / 2 + options.global_margin_m;
    r.half_window_y_m = (db.max_corner.y - db.min_corner.y) / 2 + options.global_margin_m;
    bool duplicate = false;
    for (const SearchRegion& other : regions) duplicate = duplicate || SameRegion(r, other);
    if (!duplicate) regions.push_back(r);
  }
  return Match(query, db, regions, std::vector<int>(regions.size(), -1), options);
}

ScanMatch MatchLocalMapsGlobal(const PreparedQuery& query, const PreparedMap& db, const ScanMatchOptions& options) {
  ScanMatch m;
  if (!Matchable(query, db, options)) return m;
  std::vector<SearchRegion> regions;
  const Point2 centre{(db.min_corner.x + db.max_corner.x) / 2, (db.min_corner.y + db.max_corner.y) / 2};
  const int turns = std::max(1, static_cast<int>(std::lround(360.0 / std::max(1.0, options.global_turn_deg))));
  for (int k = 0; k < turns; ++k) {
    SearchRegion r;
    r.theta = db.heading - query.heading + k * (2.0 * M_PI / turns);
    r.half_window_rad = options.global_window_deg * M_PI / 180.0;
    r.centroid_target = centre;
    r.half_window_x_m = (db.max_corner.x - db.min_corner.x) / 2 + options.global_margin_m;
    r.half_window_y_m = (db.max_corner.y - db.min_corner.y) / 2 + options.global_margin_m;
    regions.push_back(r);
  }
  return Match(query, db, regions, std::vector<int>(regions.size(), -1), options);
}

}  // namespace lmd
