#include "core/change/change_detector.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

#include "core/change/lof.h"

namespace lmd {
namespace {

constexpr uint64_t kChangeWordMask = (uint64_t{1} << 60) - 1;

double Dissimilarity(uint64_t wa, double xa, double ya, uint64_t wb, double xb, double yb, double spatial_weight) {
  const double hamming = static_cast<double>(__builtin_popcountll((wa ^ wb) & kChangeWordMask));
  if (spatial_weight == 0.0) return hamming;
  // sqrt rather than std::hypot: the same distance here, several times faster.
  return hamming + spatial_weight * std::sqrt((xa - xb) * (xa - xb) + (ya - yb) * (ya - yb));
}

// R(o * 90 deg) * (x, y) + offset.
Point2 PredictInDb(const Feature& f, const MapHit& hit) {
  double x = f.x, y = f.y;
  for (int r = 0; r < (hit.orientation & 3); ++r) {
    const double nx = -y, ny = x;
    x = nx;
    y = ny;
  }
  return {x + hit.offset.x, y + hit.offset.y};
}

Point2 PlannedToOwn(const Frame& frame, double x, double y) {
  const double c = std::cos(frame.heading), s = std::sin(frame.heading);
  return {frame.origin.x + c * x - s * y, frame.origin.y + s * x + c * y};
}

size_t FindRoot(std::vector<size_t>& parent, size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

Status ValidateChangeDetectorOptions(const ChangeDetectorOptions& o) {
  if (o.lof_k < 1) return Status::InvalidArgument("lof_k must be >= 1");
  if (!(o.lof_threshold > 0.0)) return Status::InvalidArgument("lof_threshold must be > 0");
  if (!(o.window_half_m > 0.0) || !std::isfinite(o.window_half_m))
    return Status::InvalidArgument("window_half_m must be > 0");
  if (!(o.threshold > 0.0) || !std::isfinite(o.threshold)) return Status::InvalidArgument("threshold must be > 0");
  if (!(o.spatial_weight >= 0.0) || !std::isfinite(o.spatial_weight))
    return Status::InvalidArgument("spatial_weight must be >= 0");
  if (!(o.min_denominator > 0.0) || !std::isfinite(o.min_denominator))
    return Status::InvalidArgument("min_denominator must be > 0");
  if (!(o.unrelated_distance > 0.0) || !std::isfinite(o.unrelated_distance))
    return Status::InvalidArgument("unrelated_distance must be > 0");
  if (!(o.empty_window_score > 0.0) || !std::isfinite(o.empty_window_score))
    return Status::InvalidArgument("empty_window_score must be > 0");
  if (!(o.merge_radius_m >= 0.0) || !std::isfinite(o.merge_radius_m))
    return Status::InvalidArgument("merge_radius_m must be >= 0");
  return Status::Ok();
}

namespace {

// LOF of each query feature's position; it depends on the query alone, so
// DetectChanges computes it once for all candidates.
std::vector<double> QueryLof(const Lmd& query, const ChangeDetectorOptions& options) {
  std::vector<Point2> positions(query.features.size());
  for (size_t i = 0; i < positions.size(); ++i) positions[i] = {query.features[i].x, query.features[i].y};
  return LocalOutlierFactors(positions, options.lof_k);
}

// NoveltyScores with the query's LOF given.
std::vector<double> ScoresAgainst(const Lmd& query, const std::vector<double>& lof, const MapHit& hit, const Lmd& db,
                                  const ChangeDetectorOptions& options) {
  const size_t nq = query.features.size();
  // db features sorted by x, for window look-ups.
  std::vector<uint32_t> by_x(db.features.size());
  std::iota(by_x.begin(), by_x.end(), 0u);
  std::sort(by_x.begin(), by_x.end(), [&](uint32_t a, uint32_t b) { return db.features[a].x < db.features[b].x; });
  std::vector<float> xs(by_x.size());
  for (size_t k = 0; k < by_x.size(); ++k) xs[k] = db.features[by_x[k]].x;
  const double w = options.window_half_m, lambda = options.spatial_weight;
  std::vector<uint32_t> window;
  std::vector<double> r(nq, std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < nq; ++i) {
    if (lof[i] > options.lof_threshold) continue;
    const Feature& f = query.features[i];
    const Point2 p = PredictInDb(f, hit);
    window.clear();
    auto lo = std::lower_bound(xs.begin(), xs.end(), static_cast<float>(p.x - w));
    for (size_t k = static_cast<size_t>(lo - xs.begin()); k < xs.size() && xs[k] <= p.x + w; ++k) {
      const Feature& g = db.features[by_x[k]];
      if (g.x >= p.x - w && g.y >= p.y - w && g.y <= p.y + w) window.push_back(by_x[k]);
    }
    if (window.empty()) {
      r[i] = options.empty_window_score;
      continue;
    }
    double d1 = std::numeric_limits<double>::infinity();
    uint32_t nn = window[0];
    for (uint32_t j : window) {
      const Feature& g = db.features[j];
      const double d = Dissimilarity(f.change_word, p.x, p.y, g.change_word, g.x, g.y, lambda);
      if (d < d1) d1 = d, nn = j;
    }
    double d2 = options.unrelated_distance;
    if (window.size() > 1) {
      d2 = std::numeric_limits<double>::infinity();
      const Feature& a = db.features[nn];
      for (uint32_t j : window) {
        if (j == nn) continue;
        const Feature& g = db.features[j];
        d2 = std::min(d2, Dissimilarity(a.change_word, a.x, a.y, g.change_word, g.x, g.y, lambda));
      }
    }
    r[i] = d1 / std::max(d2, options.min_denominator);
  }
  return r;
}

}  // namespace

Result<std::vector<double>> NoveltyScores(const Lmd& query, const MapHit& hit, const Lmd& db,
                                          const ChangeDetectorOptions& options) {
  Status st = ValidateChangeDetectorOptions(options);
  if (!st.ok()) return st;
  return ScoresAgainst(query, QueryLof(query, options), hit, db, options);
}

Result<std::vector<ChangeMask>> DetectChanges(const Lmd& query, const std::vector<ChangeCandidate>& candidates,
                                              const ChangeDetectorOptions& options) {
  Status st = ValidateChangeDetectorOptions(options);
  if (!st.ok()) return st;
  std::vector<ChangeMask> masks;
  const double merge2 = options.merge_radius_m * options.merge_radius_m;
  for (size_t c = 0; c < candidates.size(); ++c) {
    if (candidates[c].db == nullptr)
      return Status::InvalidArgument("candidate " + std::to_string(c) + " has no db descriptor");
  }
  const std::vector<double> lof = candidates.empty() ? std::vector<double>() : QueryLof(query, options);
  for (size_t c = 0; c < candidates.size(); ++c) {
    const std::vector<double> scores = ScoresAgainst(query, lof, candidates[c].hit, *candidates[c].db, options);
    std::vector<size_t> changed;
    for (size_t i = 0; i < scores.size(); ++i)
      if (scores[i] > options.threshold) changed.push_back(i);  // NaN (LOF-removed) compares false
    // Single-linkage clusters of change features (planned and own frames are isometric).
    std::vector<size_t> parent(changed.size());
    std::iota(parent.begin(), parent.end(), size_t{0});
    for (size_t a = 0; a < changed.size(); ++a) {
      for (size_t b = a + 1; b < changed.size(); ++b) {
        const Feature& fa = query.features[changed[a]];
        const Feature& fb = query.features[changed[b]];
        const double dx = fa.x - fb.x, dy = fa.y - fb.y;
        if (dx * dx + dy * dy < merge2) parent[FindRoot(parent, a)] = FindRoot(parent, b);
      }
    }
    std::vector<size_t> mask_of(changed.size(), SIZE_MAX);
    const size_t first = masks.size();
    for (size_t a = 0; a < changed.size(); ++a) {
      const size_t root = FindRoot(parent, a);
      if (mask_of[root] == SIZE_MAX) {
        mask_of[root] = masks.size();
        ChangeMask m;
        m.db_map_id = candidates[c].hit.map_id;
        m.map_score = candidates[c].hit.score;
        m.map_rank = candidates[c].hit.rank;
        masks.push_back(m);
      }
      ChangeMask& m = masks[mask_of[root]];
      const Feature& f = query.features[changed[a]];
      m.points.push_back(PlannedToOwn(query.frame, f.x, f.y));
      m.scores.push_back(scores[changed[a]]);
      m.score = std::max(m.score, scores[changed[a]]);
    }
    for (size_t k = first; k < masks.size(); ++k) {
      ChangeMask& m = masks[k];
      for (const Point2& p : m.points) m.centre.x += p.x, m.centre.y += p.y;
      m.centre.x /= static_cast<double>(m.points.size());
      m.centre.y /= static_cast<double>(m.points.size());
    }
  }
  std::stable_sort(masks.begin(), masks.end(), [](const ChangeMask& a, const ChangeMask& b) {
    if (a.map_score != b.map_score) return a.map_score > b.map_score;
    if (a.map_rank != b.map_rank) return a.map_rank < b.map_rank;
    return a.score > b.score;
  });
  if (options.max_masks > 0 && masks.size() > options.max_masks) masks.resize(options.max_masks);
  for (size_t k = 0; k < masks.size(); ++k) masks[k].rank = k;
  return masks;
}

}  // namespace lmd
