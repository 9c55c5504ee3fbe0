#include "bench/eval/verify.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/align/icp.h"
#include "core/align/prepared_map.h"
#include "core/align/scan_match.h"

namespace lmd::eval {

class Verifier::Query {
 public:
  lmd::PreparedQuery prepared;
};

struct Verifier::Impl {
  const std::vector<LocalMap>* maps;
  ScanMatchOptions options;
  VerifyConfig config;
  mutable std::vector<std::shared_ptr<const PreparedMap>> prepared;
  mutable std::vector<std::once_flag> once;
};

Verifier::Verifier(const std::vector<LocalMap>* maps, const VerifyConfig& config) : impl_(new Impl) {
  impl_->maps = maps;
  impl_->config = config;
  impl_->options.window_m = config.window_m;
  impl_->options.window_deg = config.window_deg;
  impl_->options.quarter_turns = config.quarter_turns;
  impl_->options.inlier_radius_m = config.inlier_radius_m;
  impl_->prepared.resize(maps->size());
  impl_->once = std::vector<std::once_flag>(maps->size());
}

Verifier::~Verifier() = default;

void Verifier::Clear() {
  impl_->prepared.assign(impl_->maps->size(), nullptr);
  impl_->once = std::vector<std::once_flag>(impl_->maps->size());
}

std::shared_ptr<const Verifier::Query> Verifier::Prepare(const LocalMap& query) const {
  auto q = std::make_shared<Query>();
  q->prepared = PrepareQuery(query, impl_->options);
  return q;
}

Alignment Verifier::Align(const Query& query, size_t db, const std::vector<Pose2>& guesses) const {
  std::call_once(impl_->once[db], [&] {
    impl_->prepared[db] = std::make_shared<PreparedMap>(PrepareMap((*impl_->maps)[db], impl_->options.map));
  });
  const PreparedMap& map = *impl_->prepared[db];
  ScanMatch best;
  bool have = false;
  if (!guesses.empty()) {
    best = MatchLocalMaps(query.prepared, map, guesses, impl_->options);
    have = true;
  }
  if (impl_->config.global_fallback && (!have || best.score < impl_->config.global_below)) {
    const ScanMatch global = MatchLocalMapsGlobal(query.prepared, map, impl_->options);
    if (!have || global.score > best.score) best = global;
  }
  Alignment a;
  a.pose = best.pose;
  a.overlap = best.score;
  const Overlap ov = MeasureOverlap(query.prepared.points, map, best.pose, impl_->config.inlier_radius_m);
  a.conflict = ov.conflict_fraction;
  // Truncated mean nearest distance after alignment.
  const double limit = std::min(0.5, map.options.neighbour_cell_m);
  double sum = 0;
  const double c = std::cos(best.pose.theta), s = std::sin(best.pose.theta);
  for (const Point2& p : query.prepared.points) {
    const Point2 t{best.pose.x + c * p.x - s * p.y, best.pose.y + s * p.x + c * p.y};
    double d2 = 0;
    sum += NearestPoint(map, t, limit, &d2) >= 0 ? std::sqrt(d2) : limit;
  }
  a.mean_dist_m = query.prepared.points.empty() ? limit : sum / query.prepared.points.size();
  return a;
}

}  // namespace lmd::eval
