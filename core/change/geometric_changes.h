// Geometric change masks: the parts of a query map that the stored maps of
// its place contradict. Once scan matching (core/localize/localizer.h) has
// placed the query in each of those maps' frames, a query point is a *change*
// when none of the maps has a point within explained_radius_m of it and at
// least one of them observed it as free space: something stands where a
// stored map's beams passed through, and no stored map shows it. (A point
// that one map saw free but another map shows is not new: something that
// comes and goes, or one map's alignment error.) Change points closer than
// merge_radius_m (single linkage) form one mask; masks with fewer than
// min_points points are dropped as noise.
//
// Masks are ranked by evidence, the sum over their points of
//   (1 if a map that saw the point free also saw free every cell of its grid
//    within free_margin_m of it (a square), else edge_weight)
//   / (1 + range / range_scale_m),
// range = distance to the nearest pose of the query's trajectory. A point at
// the edge of observed free space (beside a wall, or where the db map's
// beams ended) is what a small misalignment or a grazing beam makes; a
// point far from the robot carries the laser's angular error times its range.
// Against ranking by point count, lmd-eval's best (change success@1, mean
// over logs): 0.674 -> 0.692 on the tuning logs (orebro, fr101, intel; seed
// 1, all queries), 0.567 -> 0.598 on the six others (seed 2, 80 queries
// each); docs/results.md, row abl_mask_count.
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
  // m; <= the db map's neighbour_cell_m. 0.2 rather than 0.3 finds objects
  // standing closer to walls; the points it adds beside walls rank low by
  // their free-space margin (below). lmd-eval best, change success@1:
  // 0.692 -> 0.709 (orebro, fr101, intel; seed 1), 0.598 -> 0.615 (six other
  // logs, seed 2, 80 queries each); row abl_explained_0.3.
  double explained_radius_m = 0.2;
  double merge_radius_m = 1.0;      // m; unexplained points closer than this share a mask
  size_t min_points = 3;            // smaller groups are not reported
  // Ranking (above). false: by point count alone (the first rule; lmd-eval's
  // abl_mask_count row).
  bool rank_by_evidence = true;
  double free_margin_m = 0.2;       // m
  double edge_weight = 0.2;         // weight of a point at the edge of free space
  double range_scale_m = 5.0;       // m; range at which a point counts half
  // A change point that the query's own scans saw through more than this
  // share of the times they saw it at all (sightings.h) moved while the robot
  // mapped: a person, a door swinging, foliage. It is no change of the map
  // and is dropped before points are grouped. >= 1: keep every point.
  // lmd-eval best, change success@1: 0.709 (keep all) -> 0.721 / 0.735 /
  // 0.748 / 0.750 / 0.751 for shares 0.7 / 0.5 / 0.3 / 0.2 / 0.1 on orebro,
  // fr101 and intel (seed 1, all queries); 0.2 confirmed on the six other
  // logs (seed 2, 80 queries each): 0.615 -> 0.637, no log worse. Row
  // abl_keep_moving.
  double seen_through_share = 0.2;
  // Masks with less evidence (the ranking score above) than a floor are not
  // reported: a few points at the edge of the free space, or far from the
  // robot, are what a small misalignment or a grazing beam leaves. The floor
  // is min_evidence where the stored maps explain the rest of the query, and
  // rises by min_evidence for every floor_doubling_share of the query's
  // points that are change points outside the mask: an alignment that leaves
  // much of the query unexplained (a pose a little off, a place changed at
  // large, maps of another time) makes small masks by chance, a clean one
  // does not, so there a small mask is a change. 0: all reported;
  // floor_doubling_share <= 0: the floor is min_evidence.
  double min_evidence = 0.0;
  double floor_doubling_share = 0.0;
};

// A stored map the query was aligned to.
struct AlignedMap {
  const PreparedMap* db = nullptr;  // with free space (PrepareMap of a map with scans or trajectory)
  Pose2 pose;                       // query own frame in db own frame
  uint64_t id = 0;                  // reported as the masks' db_map_id
};

// Masks of `query_points` (query own frame) against `maps` (the stored maps
// of the query's place), best first, points in the query's own frame, score
// = evidence (point count without rank_by_evidence). `query_trajectory`
// (own frame) gives the ranges; empty: no range discount. `query_scans` (own
// frame) tell moving things (seen_through_share); empty: none dropped. A mask is credited
// to the map that saw most of its points as free (the earliest in `maps`
// among equals). No maps, or maps without free space: no masks.
std::vector<ChangeMask> GeometricChanges(const std::vector<Point2>& query_points,
                                         const std::vector<Pose2>& query_trajectory,
                                         const std::vector<Scan>& query_scans,
                                         const std::vector<AlignedMap>& maps,
                                         const GeometricChangeOptions& options = {});


}  // namespace lmd
