// The db side of scan matching, computed once per stored map and reused for
// every query matched against it: a likelihood pyramid for the correlative
// branch-and-bound search (correlative_search.h) and a bucket grid with
// per-point normals for ICP refinement and overlap scoring (icp.h).
//
// Likelihood pyramid (as in Cartographer's fast correlative scan matcher):
// level 0 is a cell_m grid whose cell value is 255 * exp(-d^2 / 2 sigma^2),
// d = distance from the cell centre to the nearest map point (0 beyond
// 3 sigma); level h holds, at cell (x, y), the maximum of level 0 over the
// 2^h x 2^h cells [x, x + 2^h) x [y, y + 2^h), so that a sum of level-h values
// bounds the level-0 score of every translation in a 2^h-cell block.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "core/grid/occupancy_grid.h"
#include "core/types.h"
#include "core/viewpoint/orientation.h"

namespace lmd {

inline constexpr int kMaxPyramidLevels = 12;  // PreparedMapOptions::levels is clamped to it

struct PreparedMapOptions {
  // m, finest correlative grid cell = search resolution; ICP refines below
  // it. 0.2 m searched 3-4x fewer poses than 0.1 m at the same success rate
  // on real logs (intel), and its grids are 4x smaller.
  double cell_m = 0.2;
  int levels = 6;               // pyramid levels 0..levels-1; coarsest block = cell_m * 2^(levels-1) (6.4 m)
  double kernel_sigma_m = 0.2;  // m, width of the likelihood kernel around each map point
  // m, bucket size of the nearest-point grid; queries within this distance
  // are found exactly (ICP correspondences and the inlier radius must not exceed it).
  double neighbour_cell_m = 0.4;
  double normal_radius_m = 0.3;  // m, neighbours used for a point's normal (PCA); >= 3 needed
  double sparse_cell_m = 0.3;    // m, cell of sparse_points
  OrientationOptions orientation;  // entropy compass for `heading`
  // Free space (PrepareMap only, maps with scans or a trajectory): beams
  // ray-cast on a grid (cell 0.1 m, cropped 12 m around the trajectory) so
  // that query points landing in space the db map saw empty count as conflicts.
  // Scans 25 cm apart and within 5 deg clear nearly the same 10 cm cells:
  // one is traced; and of consecutive beams of a scan that end in one cell,
  // one (fr079's 0.5 deg laser: 30 % fewer instructions building the free
  // space).
  bool free_space = true;
  //
  // A beam with no return clears nothing here: it met glass, a dark or
  // steep surface as often as open space, and the free space it gave put
  // one place's walls in another map's of the same place (its share of the
  // other's observed points in free space, confidence.h). On aces, fr079,
  // intel and orebro (300 queries each, in process), right answers unsure
  // only for a rival that was a map of the same place at the right pose:
  // 149 clearing 30 m, 40 clearing none. Served, held-out logs: sure 0.355
  // -> 0.394 of the queries, right 98.52 -> 98.63 %.
  GridOptions free_grid = [] {
    GridOptions grid;
    grid.min_scan_spacing_m = 0.25;
    grid.min_scan_turn_deg = 5.0;
    grid.no_return_clear_m = 0.0;
    grid.one_beam_per_end_cell = true;
    return grid;
  }();
};

// One pyramid level: value(x, y) for x in [-pad, width - pad), y alike.
struct LikelihoodLevel {
  int pad = 0;       // 2^h - 1
  int width = 0;     // level-0 width + pad
  int height = 0;
  std::vector<uint8_t> values;  // row-major, y * width + x (x, y shifted by pad)
};

struct PreparedMap {
  PreparedMapOptions options;
  std::vector<Point2> points;       // the map's finite points, own frame, in bucket order (below)
  // One of `points` per sparse_cell_m cell: shares of the map's points (in
  // another map's free space, say) measured at a fraction of the cost.
  std::vector<Point2> sparse_points;
  std::vector<Point2> normals;      // unit normal per point; (0, 0) where undefined
  Point2 min_corner, max_corner;    // bounding box of points (own frame)
  double heading = 0.0;             // rad in [0, pi/2): dominant orientation (entropy compass)
  // How far a rigid fit may put the map's own frame off because its path
  // bends (LocalMap::heading_drift_rad_per_m; MapBend); zero for a rigid map.
  struct Bend {
    double heading_sd_rad = 0.0;
    double position_sd_m = 0.0;
  } bend;

  // Likelihood pyramid; grid_origin = own-frame position of level-0 cell (0, 0)'s lower-left corner.
  Point2 grid_origin;
  int grid_width = 0, grid_height = 0;  // level-0 size in cells
  // Pyramid level h (0 <= h < options.levels; an empty level otherwise or
  // for an empty map), built on first use together with the levels below it
  // (thread-safe) and shared by copies: only a map matched against needs
  // them, and a coarse bound (CorrelativeBound) needs only the lower ones.
  // Most of a fleet's maps are prepared as queries and stored but never
  // matched against (the pyramid was half of preparing one). Built from the
  // set of `points` and the grid above, which must not change once prepared.
  const LikelihoodLevel& level(int h) const;

  // Free space of the db map (rotation 0); empty (0 x 0) when not built.
  OccupancyGrid occupancy;

  // Nearest-point buckets over a neighbour_cell_m grid anchored at
  // bucket_origin: bucket y * w + x holds points[bucket_start[k], bucket_start[k + 1]).
  Point2 bucket_origin;
  int bucket_width = 0, bucket_height = 0;
  std::vector<uint32_t> bucket_start;   // size w*h + 1

  bool empty() const { return points.empty(); }
  // True for a map from PrepareSearchGrid: points, box and pyramid only.
  bool SearchGridOnly() const { return !points.empty() && bucket_start.empty(); }
  // Approximate heap size in bytes (for caches), the pyramid counted
  // whether built yet or not.
  size_t MemoryBytes() const;

 private:
  struct LazyPyramid {
    std::mutex mutex;             // held while a level is built
    std::atomic<int> built{0};    // levels [0, built) are complete
    // Fixed storage: a level is read without the lock once `built` says it
    // is complete, while the levels above it are being built.
    std::array<LikelihoodLevel, kMaxPyramidLevels> levels;
  };
  std::shared_ptr<LazyPyramid> pyramid_ = std::make_shared<LazyPyramid>();
};

// Builds the buckets, normals and heading of `map`'s points (and its free
// space, from its scans); the pyramid follows on first use (level()). Cost
// is linear in the point count plus the grid area plus the beams (~2-10 ms
// for a real local map, about half of it the pyramid).
// Points that are not finite are dropped. Options out of range are clamped
// (cell_m >= 0.01, levels in [1, 12]). `known_heading`: the entropy compass of
// these points, when the caller has it already (a stored map's planned frame:
// same function, same points), so that it is not computed twice.
PreparedMap PrepareMap(const LocalMap& map, const PreparedMapOptions& options = {},
                       std::optional<double> known_heading = std::nullopt);
PreparedMap PreparePoints(const std::vector<Point2>& points, const PreparedMapOptions& options = {},
                          std::optional<double> known_heading = std::nullopt);

// A map for the correlative search alone (correlative_search.h): its points,
// their box and the pyramid's grid; no buckets, normals, heading or free
// space, so neither ICP nor overlap measures apply. For a grid of several
// maps' points fused (core/localize/site_grid.h). Points that are not finite
// are dropped; options are clamped as PreparePoints clamps them.
PreparedMap PrepareSearchGrid(const std::vector<Point2>& points, const PreparedMapOptions& options = {});

// PrepareSearchGrid(map.points, options) completed into PrepareMap(map,
// options, known_heading), its pyramid shared, with whatever levels it has
// built already: a map read for a coarse fit (RankByFit) and then matched
// against is gridded once. A map already complete is returned as it is.
PreparedMap CompletePreparation(PreparedMap grid, const LocalMap& map,
                                std::optional<double> known_heading = std::nullopt);

// PreparedMap::bend of `map`. Its heading drifts at a rate of up to
// heading_drift_rad_per_m, sign and size unknown (taken as uniform), so
// over its path of length L (its trajectory's, else its scans' poses') its
// end turns by up to that times L. A rigid fit of the whole map turns it to
// match its middle and leaves its frame about half that turned; a map
// matched along a stretch of its path is turned as much as the bend up to
// there, on average about as much again: heading sd = rate * L / 2 /
// sqrt(3). The frame lies up to L / 2 from the middle of its path: position
// sd = L / 2 times the heading sd (for the query's own frame, which a fit
// pins at its middle, about three times what it is; for the stored map's,
// about what it is where the query lies along its path). The length error
// of odometry is not in it: a robot states its heading drift only.
PreparedMap::Bend MapBend(const LocalMap& map);

// Index of the map point nearest to p within max_dist_m (<= neighbour_cell_m),
// or -1 if none. *dist2 (if not null) receives its squared distance.
int NearestPoint(const PreparedMap& map, const Point2& p, double max_dist_m, double* dist2 = nullptr);

// True if p (db own frame) lies in a cell the db map observed as free.
bool InFreeSpace(const PreparedMap& map, const Point2& p);

}  // namespace lmd
