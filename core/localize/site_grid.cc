#include "core/localize/site_grid.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/align/correlative_search.h"
#include "core/align/icp.h"
#include "core/localize/verification.h"
#include "core/localmap/pose_ops.h"

namespace lmd::localize_internal {
namespace {

// The newest maps of each 10 m cell fused into the site grid: where a fleet
// piles up maps of a place, a few dozen already cover it, and the grid's
// cost is linear in the points read.
constexpr size_t kSiteMapsPerCell = 32;
// Around the site's pose, each picked map is searched over a cell and a
// degree either way (the site's lattice step) before ICP.
constexpr double kPickWindowM = 0.2;
constexpr double kPickWindowDeg = 1.0;

// The site's points are thinned to one per 5 cm cell before the grid is
// built: where a fleet piles up maps of one place, dozens of maps' points lie
// on each wall, and the grid's cost is linear in them.
constexpr double kThinCellM = 0.05;

// Which kThinCellM cells of a square (corner x0, y0, side metres) hold a
// point already. Scratch per thread: one bit per cell.
class SiteThinning {
 public:
  SiteThinning(double x0, double y0, double side) : x0_(x0), y0_(y0) {
    cells_ = static_cast<int64_t>(std::ceil(side / kThinCellM)) + 1;
    bits_.assign(static_cast<size_t>((cells_ * cells_ + 63) / 64), 0);
  }
  // True for the first point of its cell (outside the square: always).
  bool First(const Point2& p) {
    const int64_t ix = static_cast<int64_t>(std::floor((p.x - x0_) / kThinCellM));
    const int64_t iy = static_cast<int64_t>(std::floor((p.y - y0_) / kThinCellM));
    if (ix < 0 || iy < 0 || ix >= cells_ || iy >= cells_) return true;
    const uint64_t k = static_cast<uint64_t>(iy * cells_ + ix);
    const uint64_t bit = uint64_t{1} << (k % 64);
    if (bits_[k / 64] & bit) return false;
    bits_[k / 64] |= bit;
    return true;
  }

 private:
  double x0_, y0_;
  int64_t cells_ = 0;
  static thread_local std::vector<uint64_t> bits_;
};
thread_local std::vector<uint64_t> SiteThinning::bits_;

// An anchored map near the prior, prepared.
struct NearMap {
  MapSource::Anchored anchored;
  std::shared_ptr<const PreparedMap> db;
};

// The turns of the query into the collection's frame that the maps'
// compasses give within the prior's heading range (those within a degree
// of each other once).
std::vector<double> CompassTurns(const LocalQuery& query, const std::vector<NearMap>& near, const Prior& prior) {
  std::vector<double> turns;
  for (const NearMap& m : near) {
    const double turn = CompassTurn(m.anchored.pose.theta + m.db->heading - query.map->heading, prior.pose.theta);
    if (std::abs(std::remainder(turn - prior.pose.theta, 2 * M_PI)) > 2 * prior.heading_sigma_rad) continue;
    const bool seen = std::any_of(turns.begin(), turns.end(), [&](double u) {
      return std::abs(std::remainder(u - turn, 2 * M_PI)) < M_PI / 180;
    });
    if (!seen) turns.push_back(turn);
  }
  return turns;
}

// SiteGridHits, less its timing.
std::vector<LocalizedHit> MatchOnSiteGrid(const LocalQuery& query, const MapSource& source, const LocalizeOptions& options,
                                          const Prior& prior, const std::function<bool(uint64_t)>& excluded,
                                          LocalizeStats* stats) {
  std::vector<LocalizedHit> hits;
  const std::vector<Point2>& points = query.match.search_points;
  if (options.prior_site_maps == 0 || points.empty() || StopAsked(options)) return hits;
  // The anchored maps the query can overlap: its points lie within `reach`
  // of its origin, which the prior puts within the window of its own.
  const double reach = QueryReach(query);
  const ScanMatchOptions window = PriorWindow(prior, options);
  const double half = window.window_m + reach + options.match.map.cell_m;
  std::vector<NearMap> near;
  for (const MapSource::Anchored& a :
       source.AnchoredNear({prior.pose.x, prior.pose.y}, window.window_m + reach, kSiteMapsPerCell, excluded)) {
    if (std::shared_ptr<const PreparedMap> db = source.Prepared(a.map_id)) near.push_back({a, std::move(db)});
  }
  // Their points there, in the collection's frame (each map's sparse points:
  // one per 0.3 m, within the likelihood kernel's reach of each other), the
  // first in each kThinCellM cell only.
  std::vector<Point2> site_points;
  SiteThinning thinning(prior.pose.x - half, prior.pose.y - half, 2 * half);
  for (const NearMap& m : near) {
    const PointTransform to_site(m.anchored.pose);
    for (const Point2& p : m.db->sparse_points) {
      const Point2 at = to_site(p);
      if (std::abs(at.x - prior.pose.x) > half || std::abs(at.y - prior.pose.y) > half) continue;
      if (thinning.First(at)) site_points.push_back(at);
    }
  }
  const PreparedMap site = PrepareSearchGrid(site_points, options.match.map);
  if (site.empty()) return hits;
  // The query's centroid within the window of where each turn puts it (the
  // search turns the query about its centroid).
  std::vector<double> turns = CompassTurns(query, near, prior);
  double half_window_deg = options.match.window_deg;
  if (turns.empty()) {
    turns.push_back(prior.pose.theta);
    half_window_deg += 2 * prior.heading_sigma_rad * 180 / M_PI;
  }
  std::vector<SearchRegion> regions;
  for (double turn : turns) {
    SearchRegion r;
    r.theta = turn;
    r.half_window_rad = half_window_deg * M_PI / 180;
    r.centroid_target = TransformPoint({prior.pose.x, prior.pose.y, turn}, query.match.centroid);
    r.half_window_x_m = r.half_window_y_m = window.window_m;
    regions.push_back(r);
  }
  const CorrelativeResult found = CorrelativeSearch(points, site, regions, window.correlative);
  ++stats->maps_matched;
  if (!found.found) return hits;
  // The maps that explain most of the query there, each matched around it.
  struct Picked {
    double overlap;
    uint64_t map_id;
    Pose2 in_map;
    std::shared_ptr<const PreparedMap> db;
  };
  std::vector<Picked> picked;
  for (const NearMap& m : near) {
    const PreparedMap& db = *m.db;
    const Pose2 in_map = Compose(Inverse(m.anchored.pose), found.pose);
    const Point2 c = TransformPoint(in_map, query.match.centroid);
    if (c.x < db.min_corner.x - reach || c.x > db.max_corner.x + reach || c.y < db.min_corner.y - reach ||
        c.y > db.max_corner.y + reach) {
      continue;  // the query cannot reach the map's points from there
    }
    picked.push_back({MeasureOverlap(points, db, in_map, options.match.inlier_radius_m).fraction, m.anchored.map_id,
                      in_map, m.db});
  }
  const size_t keep = std::min(picked.size(), options.prior_site_maps);
  std::partial_sort(picked.begin(), picked.begin() + keep, picked.end(), [](const Picked& a, const Picked& b) {
    return a.overlap != b.overlap ? a.overlap > b.overlap : a.map_id < b.map_id;
  });
  ScanMatchOptions around = window;
  around.window_m = kPickWindowM;
  around.window_deg = kPickWindowDeg;
  around.quarter_turns = false;
  for (size_t i = 0; i < keep && !StopAsked(options); ++i) {
    const Picked& p = picked[i];
    LocalizedHit hit = Scored(query, *p.db, MatchLocalMaps(query.match, *p.db, {p.in_map}, around), options);
    ++stats->maps_matched;
    hit.map_id = p.map_id;
    hit.db = p.db;
    hits.push_back(std::move(hit));
  }
  return hits;
}

}  // namespace

std::vector<LocalizedHit> SiteGridHits(const LocalQuery& query, const MapSource& source,
                                       const LocalizeOptions& options, const Prior& prior,
                                       const std::function<bool(uint64_t)>& excluded, LocalizeStats* stats) {
  const auto t = std::chrono::steady_clock::now();
  std::vector<LocalizedHit> hits = MatchOnSiteGrid(query, source, options, prior, excluded, stats);
  stats->verify_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  return hits;
}

}  // namespace lmd::localize_internal
