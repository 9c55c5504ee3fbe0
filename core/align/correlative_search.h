// Correlative scan matching by branch and bound (Olson 2009, "Real-time
// correlative scan matching"; Hess et al. 2016, Cartographer's fast
// correlative scan matcher): the pose maximising the sum of the db map's
// likelihood (prepared_map.h) at the transformed query points, exact on the
// cell_m x angle-step lattice of the search regions, found by bounding
// 2^h-cell blocks of translations with the max-pooled pyramid levels.
#pragma once

#include <functional>
#include <vector>

#include "core/align/prepared_map.h"
#include "core/types.h"

namespace lmd {

// One search region: rotations theta in [theta - half_window_rad,
// theta + half_window_rad]; translations that put the query points' centroid
// within +-half_window_{x,y}_m of `centroid_target` (db own frame). Rotating
// about the centroid decouples the angle from the translation.
struct SearchRegion {
  double theta = 0.0;            // rad
  double half_window_rad = 0.0;  // rad, >= 0
  Point2 centroid_target;        // m, db own frame
  double half_window_x_m = 0.0;  // m, >= 0
  double half_window_y_m = 0.0;  // m, >= 0
};

struct CorrelativeOptions {
  // deg; the angle step is min(this, the angle that moves the query point
  // farthest from the centroid by one cell_m), ~0.5 deg for a 10 m map.
  double max_angle_step_deg = 1.0;
  // m; translation windows wider than this per axis are clamped (guards memory/time).
  double max_half_window_m = 100.0;
  // Mean likelihood in [0, 1] a pose must exceed to be reported; blocks whose
  // bound is not above it are pruned, so a hopeless pair ends early (on real
  // logs 0.4 halved the time of wrong pairs). 0 = always report the exact best.
  double min_score = 0.35;
  // Poses to leave out: those that put the query centroid within
  // exclude_radius_m of exclude_centroid and turn within exclude_angle_rad
  // of exclude_theta. For the second-best alignment, away from the best
  // (a look-alike pose of the same map). exclude_radius_m <= 0: none.
  Point2 exclude_centroid;
  double exclude_theta = 0.0;
  double exclude_radius_m = 0.0;
  double exclude_angle_rad = 0.0;
  // Polled while searching (when set): once it returns true the search gives
  // up and finds nothing. A caller's deadline or cancellation then ends a
  // search that an unstructured map would keep busy for seconds.
  std::function<bool()> stop;
};

struct CorrelativeResult {
  bool found = false;   // false for empty inputs, no region, or nothing above min_score
  Pose2 pose;           // query own frame in db own frame
  double score = 0.0;   // mean level-0 likelihood of the query points, in [0, 1]
  size_t region = 0;    // index of the region that held the best pose
  size_t evaluations = 0;  // block scores computed (a cost measure)
};

// An upper bound of CorrelativeSearch's score over `region` at its centre
// angle (mean likelihood, [0, 1]), from the coarsest pyramid level whose
// blocks cover the window, or a finer one whose blocks are at most
// `max_block_m` wide (then one score per block of the window): a cheap way
// to rank maps before searching them, tighter the finer the blocks.
double CorrelativeBound(const std::vector<Point2>& query_points, const PreparedMap& db, const SearchRegion& region,
                        double max_block_m = 0.0);

// Best pose of `query_points` (query own frame) over all regions. The query
// points should be few (subsample to ~0.2 m) since cost is linear in them.
CorrelativeResult CorrelativeSearch(const std::vector<Point2>& query_points, const PreparedMap& db,
                                    const std::vector<SearchRegion>& regions,
                                    const CorrelativeOptions& options = {});

}  // namespace lmd
