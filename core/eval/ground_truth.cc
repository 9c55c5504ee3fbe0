#include "core/eval/ground_truth.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <thread>

#include "core/eval/point_grid.h"
#include "core/localmap/cell_set.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

constexpr double kNearestCell = 0.5;  // m, per-map nearest-point grid
constexpr double kCoarseCell = 2.0;   // m, candidate pruning grid

bool FarEnough(const LocalMap& a, const LocalMap& b, double gap) {
  return std::abs(a.truth.travel_start - b.truth.travel_start) > gap;
}

// Inverted file: cell of size `cell` -> maps with a point in that cell or one
// of its 8 neighbours. Flat, sorted by (cell, map).
class CellIndex {
 public:
  CellIndex(const std::vector<std::vector<Point2>>& maps, double cell) : cell_(cell) {
    std::vector<std::pair<uint64_t, uint32_t>> entries;
    std::vector<uint64_t> cells;
    CellSet seen;
    for (size_t j = 0; j < maps.size(); ++j) {
      Cells(maps[j], &cells);
      cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
      seen.Reset(cells.size() * 4);
      for (uint64_t k : cells) {
        const int64_t cx = static_cast<int64_t>(k >> 32) - 0x40000000;
        const int64_t cy = static_cast<int64_t>(k & 0xffffffffULL) - 0x40000000;
        for (int64_t dy = -1; dy <= 1; ++dy)
          for (int64_t dx = -1; dx <= 1; ++dx) {
            const uint64_t key = CellKey(cx + dx, cy + dy);
            if (seen.Insert(key)) entries.push_back({key, static_cast<uint32_t>(j)});
          }
      }
    }
    std::sort(entries.begin(), entries.end());
    keys_.reserve(entries.size());
    maps_.reserve(entries.size());
    for (const auto& e : entries) {
      keys_.push_back(e.first);
      maps_.push_back(e.second);
    }
  }

  // For each point of q: (*acc)[j] += 1 for every map j whose dilated cells
  // hold it. Maps whose count leaves 0 are appended to *touched (if given).
  void Accumulate(const std::vector<Point2>& q, std::vector<uint32_t>* acc, std::vector<uint32_t>* touched,
                  std::vector<uint64_t>* scratch) const {
    std::vector<uint64_t>& cells = *scratch;
    Cells(q, &cells);
    for (size_t a = 0; a < cells.size();) {
      size_t b = a;
      while (b < cells.size() && cells[b] == cells[a]) ++b;
      const uint32_t w = static_cast<uint32_t>(b - a);
      auto lo = std::lower_bound(keys_.begin(), keys_.end(), cells[a]);
      for (size_t e = static_cast<size_t>(lo - keys_.begin()); e < keys_.size() && keys_[e] == cells[a]; ++e) {
        uint32_t& v = (*acc)[maps_[e]];
        if (v == 0 && touched != nullptr) touched->push_back(maps_[e]);
        v += w;
      }
      a = b;
    }
  }

 private:
  // Sorted cell keys of the points (with repeats).
  void Cells(const std::vector<Point2>& pts, std::vector<uint64_t>* cells) const {
    cells->clear();
    for (const Point2& p : pts) cells->push_back(CellKeyOf(p.x, p.y, cell_));
    std::sort(cells->begin(), cells->end());
  }

  double cell_;
  std::vector<uint64_t> keys_;
  std::vector<uint32_t> maps_;
};

}  // namespace

std::vector<Point2> ToGlobal(const LocalMap& map) {
  std::vector<Point2> out;
  out.reserve(map.points.size());
  const double c = std::cos(map.truth.global_frame.theta), s = std::sin(map.truth.global_frame.theta);
  const double x = map.truth.global_frame.x, y = map.truth.global_frame.y;
  for (const Point2& p : map.points) out.push_back({x + c * p.x - s * p.y, y + s * p.x + c * p.y});
  return out;
}

std::vector<size_t> CandidateCounts(const std::vector<LocalMap>& maps, const GroundTruthOptions& options) {
  std::vector<double> starts;
  for (const LocalMap& m : maps)
    if (!m.points.empty()) starts.push_back(m.truth.travel_start);
  std::sort(starts.begin(), starts.end());
  std::vector<size_t> counts(maps.size(), 0);
  for (size_t i = 0; i < maps.size(); ++i) {
    const double t = maps[i].truth.travel_start;
    const size_t below = static_cast<size_t>(
        std::lower_bound(starts.begin(), starts.end(), t - options.min_travel_gap_m) - starts.begin());
    const size_t above = static_cast<size_t>(
        starts.end() - std::upper_bound(starts.begin(), starts.end(), t + options.min_travel_gap_m));
    // lower_bound counts t_j < t - gap; upper_bound leaves t_j > t + gap.
    counts[i] = below + above;
  }
  return counts;
}

std::vector<RelevantPair> FindRelevantPairs(const std::vector<LocalMap>& maps, const GroundTruthOptions& options) {
  const size_t n_maps = maps.size();
  std::vector<std::vector<Point2>> global(n_maps);
  std::vector<PointGrid> grids(n_maps);
  for (size_t j = 0; j < n_maps; ++j) {
    global[j] = ToGlobal(maps[j]);
    // Sorted by nearest-grid cell so that points of one cell are adjacent.
    std::sort(global[j].begin(), global[j].end(), [](const Point2& a, const Point2& b) {
      return CellKeyOf(a.x, a.y, kNearestCell) < CellKeyOf(b.x, b.y, kNearestCell);
    });
    if (!global[j].empty()) grids[j] = PointGrid(global[j], kNearestCell);
  }
  // Lower bounds on the mean distance, from two inverted files of dilated
  // cells: a query point outside map j's dilated cells of size c is at least
  // c away from every point of j.
  const CellIndex fine(global, kNearestCell), coarse(global, kCoarseCell);
  const std::vector<size_t> counts = CandidateCounts(maps, options);
  std::vector<std::optional<RelevantPair>> found(n_maps);
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    std::vector<uint32_t> acc_fine(n_maps, 0), acc_coarse(n_maps, 0);
    std::vector<uint32_t> touched;
    std::vector<std::pair<double, uint32_t>> survivors;  // (lower bound, map)
    std::vector<size_t> groups;                          // start of each cell's run in q
    std::vector<Point2> block;
    std::vector<uint64_t> scratch;
    for (size_t i = next++; i < n_maps; i = next++) {
      const std::vector<Point2>& q = global[i];
      const size_t n = q.size();
      if (n == 0) continue;
      touched.clear();
      coarse.Accumulate(q, &acc_coarse, &touched, &scratch);
      fine.Accumulate(q, &acc_fine, nullptr, &scratch);
      survivors.clear();
      const double dn = static_cast<double>(n);
      for (uint32_t j : touched) {
        const double a2 = acc_coarse[j], a1 = std::min<double>(acc_fine[j], a2);
        const double lower = ((dn - a2) * kCoarseCell + (a2 - a1) * kNearestCell) / dn;
        if (j != i && lower < options.max_mean_dist_m && FarEnough(maps[i], maps[j], options.min_travel_gap_m)) {
          survivors.push_back({lower, j});
        }
      }
      for (uint32_t j : touched) acc_coarse[j] = acc_fine[j] = 0;
      std::sort(survivors.begin(), survivors.end());
      groups.clear();
      for (size_t k = 0; k < n; ++k) {
        if (k == 0 || CellKeyOf(q[k].x, q[k].y, kNearestCell) != CellKeyOf(q[k - 1].x, q[k - 1].y, kNearestCell)) {
          groups.push_back(k);
        }
      }
      const size_t n_groups = groups.size();
      groups.push_back(n);
      // Groups visited in a strided order so that a bad candidate shows early.
      const size_t stride = (n_groups % 7919 == 0) ? 1 : 7919;
      // Exact mean distances, best lower bound first, each stopped as soon
      // as it cannot beat the best so far.
      double best = options.max_mean_dist_m;
      size_t best_j = n_maps;
      for (const auto& sv : survivors) {
        if (sv.first >= best) break;
        const uint32_t j = sv.second;
        const double budget = best * dn;
        double sum = 0.0;
        size_t g = 0;
        for (size_t c = 0; c < n_groups && sum < budget; ++c, g += stride) {
          if (g >= n_groups) g %= n_groups;
          const Point2& first = q[groups[g]];
          block.clear();
          grids[j].GatherBlock(static_cast<int64_t>(std::floor(first.x / kNearestCell)),
                               static_cast<int64_t>(std::floor(first.y / kNearestCell)), &block);
          for (size_t k = groups[g]; k < groups[g + 1] && sum < budget; ++k) {
            double best2 = kNearestCell * kNearestCell;
            for (const Point2& b : block) {
              const double dx = b.x - q[k].x, dy = b.y - q[k].y;
              best2 = std::min(best2, dx * dx + dy * dy);
            }
            // Within one cell: exact (all other points are farther); else search rings.
            sum += best2 < kNearestCell * kNearestCell ? std::sqrt(best2)
                                                       : grids[j].NearestDistance(q[k], budget - sum);
          }
        }
        if (sum >= budget) continue;
        best = sum / dn;
        best_j = j;
      }
      if (best_j < n_maps) found[i] = RelevantPair{i, best_j, best, counts[i]};
    }
  };
  const unsigned hw = std::thread::hardware_concurrency();
  const size_t threads = options.threads > 0 ? options.threads : std::max(1u, std::min(hw, 8u));
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  std::vector<RelevantPair> pairs;
  for (const auto& f : found)
    if (f) pairs.push_back(*f);
  return pairs;
}

double PlaceOverlap(const LocalMap& query, const LocalMap& db, double radius_m) {
  return PlaceOf(db, radius_m).Overlap(query);
}

PlaceOf::PlaceOf(const LocalMap& db, double radius_m) : radius_m_(radius_m), grid_(ToGlobal(db), radius_m) {}

double PlaceOf::Overlap(const LocalMap& query) const {
  const std::vector<Point2> q = ToGlobal(query);
  if (q.empty()) return 0.0;
  size_t within = 0;
  for (const Point2& p : q) within += grid_.AnyWithin(p, radius_m_) ? 1 : 0;
  return static_cast<double>(within) / static_cast<double>(q.size());
}

}  // namespace lmd
