#include "bench/eval/verify.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/align/icp.h"
#include "core/align/prepared_map.h"
#include "core/align/scan_match.h"
#include "core/eval/point_grid.h"

namespace lmd::eval {

class Verifier::Query {
 public:
  lmd::PreparedQuery prepared;
  PreparedMap as_map;  // the query's own points and free space (reverse conflicts)
};

struct Verifier::Impl {
  const std::vector<LocalMap>* maps;
  ScanMatchOptions options;
  VerifyConfig config;
  mutable std::vector<std::shared_ptr<const PreparedMap>> prepared;
  mutable std::vector<std::once_flag> once;
  mutable std::vector<PointGrid> grids;  // db points, own frame, 0.5 m cells

  const PreparedMap& Map(size_t db) const {
    std::call_once(once[db], [&] {
      prepared[db] = std::make_shared<PreparedMap>(PrepareMap((*maps)[db], options.map));
      grids[db] = PointGrid((*maps)[db].points, 0.5);
    });
    return *prepared[db];
  }
};

Verifier::Verifier(const std::vector<LocalMap>* maps, const VerifyConfig& config) : impl_(new Impl) {
  impl_->maps = maps;
  impl_->config = config;
  impl_->options.window_m = config.window_m;
  impl_->options.window_deg = config.window_deg;
  impl_->options.quarter_turns = config.quarter_turns;
  impl_->options.inlier_radius_m = config.inlier_radius_m;
  impl_->prepared.resize(maps->size());
  impl_->grids.resize(maps->size());
  impl_->once = std::vector<std::once_flag>(maps->size());
}

Verifier::~Verifier() = default;

void Verifier::Clear() {
  impl_->prepared.assign(impl_->maps->size(), nullptr);
  impl_->grids.assign(impl_->maps->size(), PointGrid());
  impl_->once = std::vector<std::once_flag>(impl_->maps->size());
}

std::shared_ptr<const Verifier::Query> Verifier::Prepare(const LocalMap& query) const {
  auto q = std::make_shared<Query>();
  q->prepared = PrepareQuery(query, impl_->options);
  q->as_map = PrepareMap(query, impl_->options.map);
  return q;
}

std::vector<Alignment> Verifier::Verify(const Query& query, const std::vector<size_t>& dbs,
                                       const std::vector<std::vector<Pose2>>& guesses) const {
  const VerifyConfig& config = impl_->config;
  const bool lazy = config.global_fallback && config.lazy_global && !config.always_global;
  std::vector<Alignment> out;
  bool matched = false;
  for (size_t i = 0; i < dbs.size(); ++i) {
    out.push_back(Align(query, dbs[i], guesses[i], config.global_fallback && !lazy));
    matched = matched || (!guesses[i].empty() && out.back().overlap >= config.matched_above);
  }
  if (!lazy || matched) return out;
  for (size_t i = 0; i < dbs.size(); ++i) {
    if (!guesses[i].empty() && out[i].overlap >= config.global_below) continue;
    const Alignment global = Align(query, dbs[i], {}, true);
    if (guesses[i].empty() || global.overlap > out[i].overlap) out[i] = global;
  }
  return out;
}

Alignment Verifier::Align(const Query& query, size_t db, const std::vector<Pose2>& guesses, bool global) const {
  const PreparedMap& map = impl_->Map(db);
  ScanMatch best;
  bool have = false;
  if (!guesses.empty()) {
    best = MatchLocalMaps(query.prepared, map, guesses, impl_->options);
    have = true;
  }
  if (global && (!have || impl_->config.always_global || best.score < impl_->config.global_below)) {
    const ScanMatch global = MatchLocalMapsGlobal(query.prepared, map, impl_->options);
    if (!have || global.score > best.score) best = global;
  }
  Alignment a;
  a.pose = best.pose;
  a.overlap = best.score;
  const Overlap ov = MeasureOverlap(query.prepared.points, map, best.pose, impl_->config.inlier_radius_m);
  a.conflict = ov.conflict_fraction;
  const double c0 = std::cos(best.pose.theta), s0 = std::sin(best.pose.theta);
  const Pose2 inv{-(c0 * best.pose.x + s0 * best.pose.y), -(-s0 * best.pose.x + c0 * best.pose.y), -best.pose.theta};
  a.reverse_conflict = MeasureOverlap(map.points, query.as_map, inv, impl_->config.inlier_radius_m).conflict_fraction;
  // Mean nearest distance after alignment (the ground truth's criterion).
  const PointGrid& grid = impl_->grids[db];
  double sum = 0;
  const double c = std::cos(best.pose.theta), s = std::sin(best.pose.theta);
  for (const Point2& p : query.prepared.points) {
    const Point2 t{best.pose.x + c * p.x - s * p.y, best.pose.y + s * p.x + c * p.y};
    sum += grid.empty() ? 10.0 : grid.NearestDistance(t, 10.0);
  }
  a.mean_dist_m = query.prepared.points.empty() ? 10.0 : sum / query.prepared.points.size();
  return a;
}

}  // namespace lmd::eval

namespace lmd::eval {

double Verifier::Unexplained(size_t db, const Pose2& pose, const std::vector<Point2>& points, double radius_m) const {
  if (points.empty()) return 0.0;
  const PreparedMap& map = impl_->Map(db);
  const PointGrid& grid = impl_->grids[db];
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  size_t far = 0;
  for (const Point2& p : points) {
    const Point2 t{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
    far += ((grid.empty() || grid.NearestDistance(t, radius_m) >= radius_m) && InFreeSpace(map, t)) ? 1 : 0;
  }
  return static_cast<double>(far) / static_cast<double>(points.size());
}

std::vector<ChangeMask> Verifier::Changes(const std::vector<std::pair<size_t, Pose2>>& aligned, const LocalMap& query,
                                          const GeometricChangeOptions& options) const {
  std::vector<AlignedMap> maps;
  for (const auto& [db, pose] : aligned) maps.push_back({&impl_->Map(db), pose, db});
  return GeometricChanges(query.points, query.trajectory, query.scans, maps, options);
}

}  // namespace lmd::eval
