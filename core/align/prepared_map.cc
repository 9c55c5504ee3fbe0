#include "core/align/prepared_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "core/localmap/local_map_builder.h"

namespace lmd {
namespace {

double KernelSigma(const PreparedMapOptions& o) { return std::max(1e-3, o.kernel_sigma_m); }
double KernelReach(const PreparedMapOptions& o) { return 3.0 * KernelSigma(o); }  // m; the kernel is 0 beyond
int KernelReachCells(const PreparedMapOptions& o) { return static_cast<int>(std::ceil(KernelReach(o) / o.cell_m)); }

// Level h from level h-1: max over the two half-blocks along x, then along y.
// With next.pad = prev.pad + half, next's column jx covers prev's columns
// jx - half and jx (and rows alike); prev is 0 outside its extent.
LikelihoodLevel NextLevel(const LikelihoodLevel& prev, int h) {
  const int half = 1 << (h - 1);
  LikelihoodLevel next;
  next.pad = (1 << h) - 1;
  next.width = prev.width + half;
  next.height = prev.height + half;
  const size_t pw = static_cast<size_t>(prev.width), nw = static_cast<size_t>(next.width);
  // Pass along x: prev's rows, next's width.
  thread_local std::vector<uint8_t> tmp;  // scratch, as BaseLevel's nearest2
  tmp.assign(nw * prev.height, 0);
  for (int iy = 0; iy < prev.height; ++iy) {
    const uint8_t* in = prev.values.data() + iy * pw;
    uint8_t* out = tmp.data() + iy * nw;
    for (size_t x = 0; x < pw; ++x) out[x] = in[x];
    for (size_t x = 0; x < pw; ++x) out[x + half] = std::max(out[x + half], in[x]);
  }
  // Pass along y.
  next.values.assign(nw * next.height, 0);
  for (int jy = 0; jy < next.height; ++jy) {
    uint8_t* out = next.values.data() + jy * nw;
    if (jy < prev.height) std::copy_n(tmp.data() + jy * nw, nw, out);
    if (jy >= half) {
      const uint8_t* in = tmp.data() + (jy - half) * nw;
      for (size_t x = 0; x < nw; ++x) out[x] = std::max(out[x], in[x]);
    }
  }
  return next;
}

// The level-0 grid's extent: the points' box grown by the kernel's reach.
void PlacePyramid(PreparedMap* m) {
  const PreparedMapOptions& o = m->options;
  const int r = KernelReachCells(o);
  m->grid_origin = {m->min_corner.x - (r + 1) * o.cell_m, m->min_corner.y - (r + 1) * o.cell_m};
  m->grid_width = static_cast<int>(std::ceil((m->max_corner.x - m->grid_origin.x) / o.cell_m)) + r + 2;
  m->grid_height = static_cast<int>(std::ceil((m->max_corner.y - m->grid_origin.y) / o.cell_m)) + r + 2;
}

LikelihoodLevel BaseLevel(const PreparedMap& m) {
  const PreparedMapOptions& o = m.options;
  const double sigma = KernelSigma(o);
  const double reach = KernelReach(o);
  const int r = KernelReachCells(o);
  LikelihoodLevel base;
  base.pad = 0;
  base.width = m.grid_width;
  base.height = m.grid_height;
  base.values.assign(static_cast<size_t>(base.width) * base.height, 0);
  // The value falls with distance, so a cell's value is that of its nearest
  // point: find the smallest squared distance per cell, then one exp per cell.
  const double reach2 = reach * reach;
  // Per-thread scratch: a fresh grid-sized allocation per map cost more in
  // page faults than the search that fills it (a cold query prepares ~50).
  // A thread keeps 9 bytes per cell of the largest grid it built (a local
  // map's: well under 1 MB; a site grid's: a few MB).
  thread_local std::vector<double> nearest2;
  nearest2.assign(base.values.size(), std::numeric_limits<double>::infinity());
  for (const Point2& p : m.points) {
    const int cx = static_cast<int>(std::floor((p.x - m.grid_origin.x) / o.cell_m));
    const int cy = static_cast<int>(std::floor((p.y - m.grid_origin.y) / o.cell_m));
    for (int y = std::max(0, cy - r); y <= std::min(base.height - 1, cy + r); ++y) {
      const double dy = m.grid_origin.y + (y + 0.5) * o.cell_m - p.y;
      for (int x = std::max(0, cx - r); x <= std::min(base.width - 1, cx + r); ++x) {
        const double dx = m.grid_origin.x + (x + 0.5) * o.cell_m - p.x;
        double& cell = nearest2[static_cast<size_t>(y) * base.width + x];
        cell = std::min(cell, dx * dx + dy * dy);
      }
    }
  }
  const double inv2s2 = 1.0 / (2.0 * sigma * sigma);
  for (size_t k = 0; k < nearest2.size(); ++k) {
    if (nearest2[k] <= reach2) base.values[k] = static_cast<uint8_t>(std::lround(255.0 * std::exp(-nearest2[k] * inv2s2)));
  }
  return base;
}

// Sorts the points by bucket (row-major, stable), so that a bucket, and a
// run of buckets along a row, is one contiguous range of points.
void BuildBuckets(PreparedMap* m) {
  const double c = m->options.neighbour_cell_m;
  m->bucket_origin = {m->min_corner.x - c, m->min_corner.y - c};
  m->bucket_width = static_cast<int>(std::floor((m->max_corner.x - m->bucket_origin.x) / c)) + 2;
  m->bucket_height = static_cast<int>(std::floor((m->max_corner.y - m->bucket_origin.y) / c)) + 2;
  const size_t cells = static_cast<size_t>(m->bucket_width) * m->bucket_height;
  std::vector<uint32_t> cell_of(m->points.size());
  m->bucket_start.assign(cells + 1, 0);
  for (size_t i = 0; i < m->points.size(); ++i) {
    const int bx = static_cast<int>(std::floor((m->points[i].x - m->bucket_origin.x) / c));
    const int by = static_cast<int>(std::floor((m->points[i].y - m->bucket_origin.y) / c));
    cell_of[i] = static_cast<uint32_t>(by * m->bucket_width + bx);
    ++m->bucket_start[cell_of[i] + 1];
  }
  for (size_t k = 0; k < cells; ++k) m->bucket_start[k + 1] += m->bucket_start[k];
  std::vector<Point2> sorted(m->points.size());
  std::vector<uint32_t> fill(m->bucket_start.begin(), m->bucket_start.end() - 1);
  for (size_t i = 0; i < m->points.size(); ++i) sorted[fill[cell_of[i]]++] = m->points[i];
  m->points = std::move(sorted);
}

// Calls f(index) for every map point in the 3x3 buckets around p (a row of
// buckets is one contiguous range of points).
template <typename F>
void ForNeighbourBuckets(const PreparedMap& m, const Point2& p, F&& f) {
  const double c = m.options.neighbour_cell_m;
  const double fx = std::floor((p.x - m.bucket_origin.x) / c);
  const double fy = std::floor((p.y - m.bucket_origin.y) / c);
  if (!(fx >= -1.0 && fy >= -1.0 && fx <= m.bucket_width && fy <= m.bucket_height)) return;  // also NaN
  const int bx = static_cast<int>(fx), by = static_cast<int>(fy);
  const int x0 = std::max(0, bx - 1), x1 = std::min(m.bucket_width - 1, bx + 1);
  if (x0 > x1) return;
  for (int y = std::max(0, by - 1); y <= std::min(m.bucket_height - 1, by + 1); ++y) {
    const size_t row = static_cast<size_t>(y) * m.bucket_width;
    for (uint32_t j = m.bucket_start[row + x0], end = m.bucket_start[row + x1 + 1]; j < end; ++j) f(j);
  }
}

void BuildNormals(PreparedMap* m) {
  const double r2 = m->options.normal_radius_m * m->options.normal_radius_m;
  m->normals.assign(m->points.size(), Point2{0, 0});
  for (size_t i = 0; i < m->points.size(); ++i) {
    const Point2 p = m->points[i];
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    int n = 0;
    ForNeighbourBuckets(*m, p, [&](uint32_t j) {
      const double dx = m->points[j].x - p.x, dy = m->points[j].y - p.y;
      if (dx * dx + dy * dy > r2) return;
      sx += dx; sy += dy; sxx += dx * dx; sxy += dx * dy; syy += dy * dy;
      ++n;
    });
    if (n < 3) continue;
    const double mx = sx / n, my = sy / n;
    Eigen::Matrix2d cov;
    cov << sxx / n - mx * mx, sxy / n - mx * my, sxy / n - mx * my, syy / n - my * my;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
    const Eigen::Vector2d ev = es.eigenvalues();  // ascending
    if (!(ev(1) > 0) || ev(0) > 0.2 * ev(1)) continue;  // not line-like
    const Eigen::Vector2d nrm = es.eigenvectors().col(0);
    m->normals[i] = {nrm.x(), nrm.y()};
  }
}

}  // namespace

const LikelihoodLevel& PreparedMap::level(int h) const {
  static const LikelihoodLevel kNone;
  if (empty() || h < 0 || h >= std::min(options.levels, kMaxPyramidLevels)) return kNone;
  LazyPyramid& pyramid = *pyramid_;
  if (pyramid.built.load(std::memory_order_acquire) <= h) {
    std::lock_guard<std::mutex> lock(pyramid.mutex);
    for (int next = pyramid.built.load(std::memory_order_relaxed); next <= h; ++next) {
      pyramid.levels[next] = next == 0 ? BaseLevel(*this) : NextLevel(pyramid.levels[next - 1], next);
      pyramid.built.store(next + 1, std::memory_order_release);
    }
  }
  return pyramid.levels[static_cast<size_t>(h)];
}

size_t PreparedMap::MemoryBytes() const {
  size_t bytes = (points.size() * 2 + sparse_points.size()) * sizeof(Point2) + bucket_start.size() * 4;
  if (!empty()) {
    for (int h = 0; h < options.levels; ++h) {
      const size_t pad = (size_t{1} << h) - 1;
      bytes += (static_cast<size_t>(grid_width) + pad) * (static_cast<size_t>(grid_height) + pad);
    }
  }
  bytes += occupancy.cells().size();
  return bytes;
}

PreparedMap PrepareSearchGrid(const std::vector<Point2>& points, const PreparedMapOptions& options) {
  PreparedMap m;
  m.options = options;
  m.options.cell_m = std::max(0.01, options.cell_m);
  m.options.levels = std::min(kMaxPyramidLevels, std::max(1, options.levels));
  m.options.neighbour_cell_m = std::max(0.01, options.neighbour_cell_m);
  m.points.reserve(points.size());
  for (const Point2& p : points) {
    if (std::isfinite(p.x) && std::isfinite(p.y)) m.points.push_back(p);
  }
  if (m.points.empty()) return m;
  m.min_corner = m.max_corner = m.points[0];
  for (const Point2& p : m.points) {
    m.min_corner.x = std::min(m.min_corner.x, p.x);
    m.min_corner.y = std::min(m.min_corner.y, p.y);
    m.max_corner.x = std::max(m.max_corner.x, p.x);
    m.max_corner.y = std::max(m.max_corner.y, p.y);
  }
  PlacePyramid(&m);
  return m;
}

namespace {

// PreparePoints' part after PrepareSearchGrid.
void AddPointStructures(PreparedMap* m, std::optional<double> known_heading) {
  const PreparedMapOptions& o = m->options;
  m->heading = known_heading ? *known_heading : EstimateDominantOrientation(m->points, o.orientation);
  m->sparse_points = DeduplicatePoints(m->points, std::max(0.01, o.sparse_cell_m));
  BuildBuckets(m);  // reorders the points, not their set: the pyramid stays valid
  BuildNormals(m);
}

}  // namespace

PreparedMap PreparePoints(const std::vector<Point2>& points, const PreparedMapOptions& options,
                          std::optional<double> known_heading) {
  PreparedMap m = PrepareSearchGrid(points, options);
  if (!m.empty()) AddPointStructures(&m, known_heading);
  return m;
}

PreparedMap PrepareMap(const LocalMap& map, const PreparedMapOptions& options, std::optional<double> known_heading) {
  return CompletePreparation(PrepareSearchGrid(map.points, options), map, known_heading);
}

PreparedMap CompletePreparation(PreparedMap grid, const LocalMap& map, std::optional<double> known_heading) {
  if (grid.empty() || !grid.SearchGridOnly()) return grid;
  AddPointStructures(&grid, known_heading);
  grid.bend = MapBend(map);
  if (grid.options.free_space && (!map.scans.empty() || !map.trajectory.empty())) {
    grid.occupancy = BuildOccupancyGrid(map, 0.0, grid.options.free_grid);
  }
  return grid;
}

PreparedMap::Bend MapBend(const LocalMap& map) {
  if (map.heading_drift_rad_per_m == 0) return {};  // a rigid map: no path to walk
  std::vector<Pose2> scan_poses;
  if (map.trajectory.empty()) {
    for (const Scan& scan : map.scans) scan_poses.push_back(scan.pose);
  }
  const std::vector<Pose2>& path = map.trajectory.empty() ? scan_poses : map.trajectory;
  double path_m = 0.0;
  for (size_t i = 1; i < path.size(); ++i) path_m += std::hypot(path[i].x - path[i - 1].x, path[i].y - path[i - 1].y);
  PreparedMap::Bend bend;
  bend.heading_sd_rad = map.heading_drift_rad_per_m * path_m / 2 / std::sqrt(3.0);
  bend.position_sd_m = path_m / 2 * bend.heading_sd_rad;
  return bend;
}

bool InFreeSpace(const PreparedMap& map, const Point2& p) {
  if (map.occupancy.width() <= 1 || !std::isfinite(p.x) || !std::isfinite(p.y)) return false;
  const double fx = std::floor((p.x - map.occupancy.min_x()) / map.occupancy.cell_m());
  const double fy = std::floor((p.y - map.occupancy.min_y()) / map.occupancy.cell_m());
  if (!(fx >= 0 && fy >= 0 && fx < map.occupancy.width() && fy < map.occupancy.height())) return false;
  return map.occupancy.at(static_cast<int>(fx), static_cast<int>(fy)) == CellState::kFree;
}

int NearestPoint(const PreparedMap& map, const Point2& p, double max_dist_m, double* dist2) {
  if (map.points.empty()) return -1;
  const double inv_c = 1.0 / map.options.neighbour_cell_m;
  const double radius = std::min(max_dist_m, map.options.neighbour_cell_m);
  // Bucket coordinates of p; outside [-1, size] nothing is within reach.
  const double u = (p.x - map.bucket_origin.x) * inv_c, v = (p.y - map.bucket_origin.y) * inv_c;
  if (!(u >= -1.0 && v >= -1.0 && u < map.bucket_width + 1.0 && v < map.bucket_height + 1.0)) return -1;  // also NaN
  const int by = static_cast<int>(v + 1.0) - 1;  // floor, as v >= -1
  double best = radius * radius;
  int best_index = -1;
  // p's own row of buckets first: the nearest point found there narrows the
  // columns searched and usually rules the other two rows out.
  for (const int y : {by, by - 1, by + 1}) {
    if (y < 0 || y >= map.bucket_height) continue;
    // Margins of 1e-9 m keep a point at exactly the best distance despite rounding.
    const double gap = std::max(0.0, (y < by ? v - (y + 1) : y > by ? y - v : 0.0) * map.options.neighbour_cell_m - 1e-9);
    if (gap * gap > best) continue;
    const double r = (std::sqrt(best) + 1e-9) * inv_c;
    const int x0 = std::max(0, static_cast<int>(u - r + 1.0) - 1);
    const int x1 = std::min(map.bucket_width - 1, static_cast<int>(u + r + 1.0) - 1);
    if (x0 > x1) continue;
    const size_t row = static_cast<size_t>(y) * map.bucket_width;
    for (uint32_t j = map.bucket_start[row + x0], end = map.bucket_start[row + x1 + 1]; j < end; ++j) {
      const double dx = map.points[j].x - p.x, dy = map.points[j].y - p.y;
      const double d2 = dx * dx + dy * dy;
      if (d2 <= best) {
        best = d2;
        best_index = static_cast<int>(j);
      }
    }
  }
  if (best_index >= 0 && dist2) *dist2 = best;
  return best_index;
}

}  // namespace lmd
