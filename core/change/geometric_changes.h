// Geometric change masks: the parts of a query map that the stored maps of
// its place contradict. Once scan matching (core/align/verify_hits.h) has
// placed the query in each of those maps' frames, a query point is a *change*
// when none of the maps has a point within explained_radius_m of it and at
// least one of them observed it as free space: something stands where a
// stored map's beams passed through, and no stored map shows it. (A point
// that one map saw free but another map shows is not new: something that
// comes and goes, or one map's alignment error.) Change points closer than
// merge_radius_m (single linkage) form one mask; masks with fewer than
// min_points points are dropped as noise; the rest are ranked by point count.
//
// This complements the paper's descriptor-level detector (change_detector.h,
// LOF + NN-d): it needs metric poses but sees every point, not only the
// interest points, and it never takes space no stored map observed for a
// change.
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

// A stored map the query was aligned to.
struct AlignedMap {
  const PreparedMap* db = nullptr;  // with free space (PrepareMap of a map with scans or trajectory)
  Pose2 pose;                       // query own frame in db own frame
  uint64_t id = 0;                  // reported as the masks' db_map_id
};

// Masks of `query_points` (query own frame) against `maps` (the stored maps
// of the query's place), best first, points in the query's own frame, score
// = point count. A mask is credited to the map that saw most of its points
// as free (the earliest in `maps` among equals). No maps, or maps without
// free space: no masks.
std::vector<ChangeMask> GeometricChanges(const std::vector<Point2>& query_points, const std::vector<AlignedMap>& maps,
                                         const GeometricChangeOptions& options = {});

}  // namespace lmd
