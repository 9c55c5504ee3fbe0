#include "core/align/correlative_search.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lmd {
namespace {

// The query points rotated by one angle, in level-0 cell coordinates of the
// db grid, with their allowed block of cell offsets.
struct Rotation {
  double theta = 0.0;
  Point2 target;  // where the centroid lands at offset (0, 0)
  size_t region = 0;
  bool near_excluded = false;  // within the excluded angle (CorrelativeOptions::exclude_*)
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // offsets (cells), inclusive
  std::vector<int32_t> cx, cy;
};

struct Block {
  int32_t rotation;
  int32_t dx, dy;
  int64_t score;
};

int64_t ScoreAt(const LikelihoodLevel& level, const Rotation& r, int dx, int dy) {
  const int ox = dx + level.pad, oy = dy + level.pad;
  const uint8_t* values = level.values.data();
  const unsigned w = static_cast<unsigned>(level.width), h = static_cast<unsigned>(level.height);
  int64_t sum = 0;
  const size_t n = r.cx.size();
  for (size_t i = 0; i < n; ++i) {
    const unsigned x = static_cast<unsigned>(r.cx[i] + ox), y = static_cast<unsigned>(r.cy[i] + oy);
    if (x < w && y < h) sum += values[y * w + x];
  }
  return sum;
}

// ScoreAt of a block's four children in one pass over the points: sums[k]
// for the offsets (dx, dy) + (0, 0), (0, half), (half, 0), (half, half).
void ScoreChildren(const LikelihoodLevel& level, const Rotation& r, int dx, int dy, int half, int64_t sums[4]) {
  const int ox = dx + level.pad, oy = dy + level.pad;
  const uint8_t* values = level.values.data();
  const unsigned w = static_cast<unsigned>(level.width), h = static_cast<unsigned>(level.height);
  const unsigned step = static_cast<unsigned>(half);
  int64_t s00 = 0, s10 = 0, s01 = 0, s11 = 0;
  const size_t n = r.cx.size();
  for (size_t i = 0; i < n; ++i) {
    const unsigned x = static_cast<unsigned>(r.cx[i] + ox), y = static_cast<unsigned>(r.cy[i] + oy);
    const unsigned x2 = x + step, y2 = y + step;
    const bool in_x = x < w, in_x2 = x2 < w;
    if (y < h) {
      const uint8_t* row = values + static_cast<size_t>(y) * w;
      if (in_x) s00 += row[x];
      if (in_x2) s10 += row[x2];
    }
    if (y2 < h) {
      const uint8_t* row = values + static_cast<size_t>(y2) * w;
      if (in_x) s01 += row[x];
      if (in_x2) s11 += row[x2];
    }
  }
  sums[0] = s00, sums[1] = s01, sums[2] = s10, sums[3] = s11;
}

class BranchAndBound {
 public:
  BranchAndBound(const PreparedMap& db, const std::vector<Rotation>& rotations, const CorrelativeOptions& options)
      : db_(db), rotations_(rotations), options_(options) {}

  // True when every translation of the block of 2^level cells at (dx, dy)
  // is excluded: the excluded disk is convex, so its four corners suffice.
  bool Excluded(const Block& b, int level) const {
    const Rotation& r = rotations_[b.rotation];
    if (!r.near_excluded) return false;
    const double cell = db_.options.cell_m, r2 = options_.exclude_radius_m * options_.exclude_radius_m;
    const int span = (1 << level) - 1;
    for (int cx : {b.dx, b.dx + span}) {
      for (int cy : {b.dy, b.dy + span}) {
        const double x = r.target.x + cx * cell - options_.exclude_centroid.x;
        const double y = r.target.y + cy * cell - options_.exclude_centroid.y;
        if (x * x + y * y > r2) return false;
      }
    }
    return true;
  }

  // Depth-first, best child first; candidates at `level` sorted by score.
  void Search(int level, std::vector<Block>& candidates) {
    for (const Block& c : candidates) {
      if (c.score <= best_.score) break;  // sorted: nothing better below
      if (Stopped()) return;
      if (Excluded(c, level)) continue;
      if (level == 0) {
        best_ = c;
        continue;
      }
      const int half = 1 << (level - 1);
      const Rotation& r = rotations_[c.rotation];
      int64_t sums[4];  // (0, 0), (0, half), (half, 0), (half, half)
      ScoreChildren(db_.level(level - 1), r, c.dx, c.dy, half, sums);
      std::vector<Block> children;
      children.reserve(4);
      for (int ox = 0, k = 0; ox <= half; ox += half) {
        const int dx = c.dx + ox;
        for (int oy = 0; oy <= half; oy += half, ++k) {
          const int dy = c.dy + oy;
          if (dx > r.x1 || dy > r.y1) continue;
          children.push_back({c.rotation, dx, dy, sums[k]});
          ++evaluations_;
        }
      }
      std::sort(children.begin(), children.end(),
                [](const Block& a, const Block& b) { return a.score > b.score; });
      Search(level - 1, children);
    }
  }

  // Whether options.stop asked to give up: polled on every call of Poll,
  // on every kStopPoll-th of Stopped (a block's children cost one pass over
  // the points; a rotation's top-level blocks, many).
  bool Poll() {
    if (!stopped_ && options_.stop) stopped_ = options_.stop();
    return stopped_;
  }
  bool Stopped() {
    constexpr unsigned kStopPoll = 256;
    return ++polls_ % kStopPoll == 0 ? Poll() : stopped_;
  }
  bool stopped() const { return stopped_; }

  Block best_{-1, 0, 0, 0};
  size_t evaluations_ = 0;

 private:
  unsigned polls_ = 0;
  bool stopped_ = false;
  const PreparedMap& db_;
  const std::vector<Rotation>& rotations_;
  const CorrelativeOptions& options_;
};

}  // namespace

double CorrelativeBound(const std::vector<Point2>& query_points, const PreparedMap& db, const SearchRegion& region,
                        double max_block_m) {
  if (query_points.empty() || db.empty()) return 0.0;
  const double cell = db.options.cell_m;
  Point2 centroid{0, 0};
  for (const Point2& p : query_points) centroid.x += p.x, centroid.y += p.y;
  centroid.x /= query_points.size(), centroid.y /= query_points.size();
  Rotation r;
  r.theta = region.theta;
  const double c = std::cos(r.theta), s = std::sin(r.theta);
  for (const Point2& p : query_points) {
    const double qx = p.x - centroid.x, qy = p.y - centroid.y;
    const double x = c * qx - s * qy + region.centroid_target.x, y = s * qx + c * qy + region.centroid_target.y;
    r.cx.push_back(static_cast<int32_t>(std::clamp(std::floor((x - db.grid_origin.x) / cell), -1.0e8, 1.0e8)));
    r.cy.push_back(static_cast<int32_t>(std::clamp(std::floor((y - db.grid_origin.y) / cell), -1.0e8, 1.0e8)));
  }
  const int wx = static_cast<int>(std::ceil(std::max(0.0, region.half_window_x_m) / cell));
  const int wy = static_cast<int>(std::ceil(std::max(0.0, region.half_window_y_m) / cell));
  int top = 0;
  while (top + 1 < db.options.levels && (1 << top) < 2 * std::max(wx, wy) + 1) ++top;
  while (max_block_m > 0 && top > 0 && (1 << top) * cell > max_block_m + 1e-9) --top;
  const LikelihoodLevel& level = db.level(top);
  int64_t best = 0;
  for (int dx = -wx; dx <= wx; dx += 1 << top) {
    for (int dy = -wy; dy <= wy; dy += 1 << top) best = std::max(best, ScoreAt(level, r, dx, dy));
  }
  return static_cast<double>(best) / (255.0 * query_points.size());
}

CorrelativeResult CorrelativeSearch(const std::vector<Point2>& query_points, const PreparedMap& db,
                                    const std::vector<SearchRegion>& regions,
                                    const CorrelativeOptions& options) {
  CorrelativeResult result;
  if (query_points.empty() || db.empty() || regions.empty()) return result;
  const double cell = db.options.cell_m;
  Point2 centroid{0, 0};
  for (const Point2& p : query_points) {
    centroid.x += p.x;
    centroid.y += p.y;
  }
  centroid.x /= query_points.size();
  centroid.y /= query_points.size();
  double radius = 0.0;
  for (const Point2& p : query_points) radius = std::max(radius, std::hypot(p.x - centroid.x, p.y - centroid.y));
  double step = options.max_angle_step_deg * M_PI / 180.0;
  if (radius > cell) step = std::min(step, std::acos(1.0 - cell * cell / (2.0 * radius * radius)));
  step = std::max(step, 1e-4);

  // Rotations of every region.
  std::vector<Rotation> rotations;
  const double max_half = std::max(0.0, options.max_half_window_m);
  for (size_t ri = 0; ri < regions.size(); ++ri) {
    if (options.stop && options.stop()) return result;
    const SearchRegion& reg = regions[ri];
    if (!std::isfinite(reg.theta) || !std::isfinite(reg.centroid_target.x) || !std::isfinite(reg.centroid_target.y)) {
      continue;
    }
    const int n_angle = static_cast<int>(std::ceil(std::max(0.0, reg.half_window_rad) / step));
    const int wx = static_cast<int>(std::ceil(std::min(max_half, std::max(0.0, reg.half_window_x_m)) / cell));
    const int wy = static_cast<int>(std::ceil(std::min(max_half, std::max(0.0, reg.half_window_y_m)) / cell));
    for (int a = -n_angle; a <= n_angle; ++a) {
      Rotation r;
      r.theta = reg.theta + a * step;
      r.target = reg.centroid_target;
      r.region = ri;
      r.x0 = -wx; r.x1 = wx; r.y0 = -wy; r.y1 = wy;
      r.near_excluded = options.exclude_radius_m > 0 &&
                        std::abs(std::remainder(r.theta - options.exclude_theta, 2.0 * M_PI)) <= options.exclude_angle_rad;
      const double c = std::cos(r.theta), s = std::sin(r.theta);
      r.cx.resize(query_points.size());
      r.cy.resize(query_points.size());
      for (size_t i = 0; i < query_points.size(); ++i) {
        const double qx = query_points[i].x - centroid.x, qy = query_points[i].y - centroid.y;
        const double x = c * qx - s * qy + r.target.x, y = s * qx + c * qy + r.target.y;
        // Clamp far-away points well outside any grid (keeps int arithmetic safe).
        const double fx = std::floor((x - db.grid_origin.x) / cell), fy = std::floor((y - db.grid_origin.y) / cell);
        r.cx[i] = static_cast<int32_t>(std::max(-1.0e8, std::min(1.0e8, fx)));
        r.cy[i] = static_cast<int32_t>(std::max(-1.0e8, std::min(1.0e8, fy)));
      }
      rotations.push_back(std::move(r));
    }
  }
  if (rotations.empty()) return result;

  // Start at the lowest level whose block covers every window: the levels
  // above would each score one block per rotation and prune nothing.
  int widest = 1;
  for (const Rotation& r : rotations) widest = std::max({widest, r.x1 - r.x0 + 1, r.y1 - r.y0 + 1});
  int top = 0;
  while (top + 1 < db.options.levels && (1 << top) < widest) ++top;
  const int top_step = 1 << top;
  std::vector<Block> candidates;
  BranchAndBound bnb(db, rotations, options);
  bnb.best_.score = static_cast<int64_t>(std::floor(std::max(0.0, options.min_score) * 255.0 * query_points.size()));
  // Seed the bound with the exact scores at the regions' centres (offset 0):
  // a guess is usually near the optimum, so most blocks are pruned at once.
  for (size_t k = 0; k < rotations.size(); ++k) {
    const int64_t centre = ScoreAt(db.level(0), rotations[k], 0, 0);
    const Block seed{static_cast<int32_t>(k), 0, 0, centre};
    if (centre > bnb.best_.score && !bnb.Excluded(seed, 0)) bnb.best_ = seed;
  }
  const LikelihoodLevel& top_level = db.level(top);
  for (size_t k = 0; k < rotations.size(); ++k) {
    if (bnb.Poll()) return result;
    const Rotation& r = rotations[k];
    for (int dx = r.x0; dx <= r.x1; dx += top_step) {
      for (int dy = r.y0; dy <= r.y1; dy += top_step) {
        candidates.push_back({static_cast<int32_t>(k), dx, dy, ScoreAt(top_level, r, dx, dy)});
      }
    }
  }
  bnb.evaluations_ = candidates.size();
  std::sort(candidates.begin(), candidates.end(), [](const Block& a, const Block& b) { return a.score > b.score; });
  bnb.Search(top, candidates);
  if (bnb.stopped()) return result;
  result.evaluations = bnb.evaluations_;
  if (bnb.best_.rotation < 0) {
    bnb.best_ = {0, 0, 0, 0};  // nothing above min_score: report the first rotation's centre, score 0
  } else {
    result.found = true;
  }
  const Rotation& r = rotations[bnb.best_.rotation];
  const double c = std::cos(r.theta), s = std::sin(r.theta);
  const Point2 land{r.target.x + bnb.best_.dx * cell, r.target.y + bnb.best_.dy * cell};
  result.pose = {land.x - (c * centroid.x - s * centroid.y), land.y - (s * centroid.x + c * centroid.y),
                 std::remainder(r.theta, 2.0 * M_PI)};
  result.score = static_cast<double>(bnb.best_.score) / (255.0 * query_points.size());
  result.region = r.region;
  return result;
}

}  // namespace lmd
