// Geometric change masks: the parts of a query map that a verified db map
// contradicts. Once scan matching (core/align/verify_hits.h) has placed the
// query in a db map's frame, a query point is *unexplained* when no db point
// lies within explained_radius_m of it and it falls in space the db map
// observed as free: something stands where the db map's beams passed through.
// Unexplained points closer than merge_radius_m (single linkage) form one
// mask; masks with fewer than min_points points are dropped as noise (range
// noise, a person walking by); the rest are ranked by their point count.
//
// This complements the paper's descriptor-level detector (change_detector.h,
// LOF + NN-d): it needs the metric pose but sees every point, not only the
// interest points, and it cannot mistake space the db map never observed for
// a change.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/align/prepared_map.h"
#include "core/change/change_detector.h"
#include "core/types.h"

namespace lmd {

struct GeometricChangeOptions {
  double explained_radius_m = 0.3;  // m; <= the db map's neighbour_cell_m
  double merge_radius_m = 1.0;      // m; unexplained points closer than this share a mask
  size_t min_points = 3;            // smaller groups are not reported
};

// Masks of `query_points` (query own frame) against `db` with the query at
// `pose` (query own frame in db own frame), best first. Each mask's points
// are in the query's own frame; score = point count; db_map_id as given.
// A db map without free space (no scans or trajectory) explains nothing and
// contradicts nothing: no masks.
std::vector<ChangeMask> GeometricChanges(const std::vector<Point2>& query_points, const PreparedMap& db,
                                         const Pose2& pose, uint64_t db_map_id,
                                         const GeometricChangeOptions& options = {});

}  // namespace lmd
