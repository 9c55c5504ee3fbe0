// Ground truth of the evaluation protocol (DESIGN.md §4): which stored map is
// the relevant one for each query, and how much two maps overlap. Reads
// LocalMap::truth (global frames, travel); no method may.
#pragma once

#include <cstddef>
#include <vector>

#include "core/eval/point_grid.h"
#include "core/types.h"

namespace lmd {

struct GroundTruthOptions {
  double min_travel_gap_m = 10.0;  // m; candidates start more than this away (paper: 10)
  double max_mean_dist_m = 0.5;    // m; a query counts if the best mean is below (paper: 0.5)
  size_t threads = 0;              // worker threads; 0 = hardware concurrency (at most 8)
};

// One counted query.
struct RelevantPair {
  size_t query;        // index into maps
  size_t relevant;     // index of the candidate with the smallest mean distance
  double mean_dist_m;  // mean over query points of the distance to the nearest
                       //   point of `relevant` (global frame); < max_mean_dist_m
  size_t candidates;   // number of candidates of this query
};

// For every map (as query): candidates = maps whose truth.travel_start differs
// by more than min_travel_gap_m; the relevant map = the candidate with the
// smallest mean nearest-point distance; the query is returned only if that
// distance is below max_mean_dist_m. Sorted by query. Maps without points are
// never queries nor relevant. Exact; fast through a coarse cell index and
// per-map hash grids (a 5000-map log in seconds).
std::vector<RelevantPair> FindRelevantPairs(const std::vector<LocalMap>& maps,
                                            const GroundTruthOptions& options = {});

// Number of candidates of each map as a query (same rule, all maps).
std::vector<size_t> CandidateCounts(const std::vector<LocalMap>& maps,
                                    const GroundTruthOptions& options = {});

// The map's points in the log's frame (through truth.global_frame).
std::vector<Point2> ToGlobal(const LocalMap& map);

// Fraction of the query's points (global frame) within radius_m of some point
// of db (global frame); 0 if the query has no points.
double PlaceOverlap(const LocalMap& query, const LocalMap& db, double radius_m = 0.3);

// PlaceOverlap against one stored map, its points gridded once, for scoring
// many queries against it.
class PlaceOf {
 public:
  explicit PlaceOf(const LocalMap& db, double radius_m = 0.3);
  double Overlap(const LocalMap& query) const;

 private:
  double radius_m_;
  PointGrid grid_;
};

}  // namespace lmd
