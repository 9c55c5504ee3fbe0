// Geometric verification for lmd-eval's "best" pipeline: aligns a query
// map's points to a candidate db map's with the scan matcher of core/align
// (correlative search + ICP) and reports the metric pose and the overlap.
// Kept behind this header (pimpl) so that lmd-eval's retrieval code needs no
// scan-matcher headers.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

#include "core/change/change_detector.h"
#include "core/change/geometric_changes.h"
#include "core/types.h"

namespace lmd::eval {

struct VerifyConfig {
  double window_m = 1.0;          // m, translation window around each guess (per axis)
  double window_deg = 3.0;        // deg, rotation window around each guess (ScanMatchOptions)
  bool quarter_turns = false;     // also try each guess turned by 90, 180, 270 deg (the kernel
                                  // already chose the best of the 4 orientations)
  bool global_fallback = true;    // guess-free search when the guided match is poor
  double global_below = 0.5;      // overlap under which the guess-free search runs
  // The guess-free search runs only for queries none of whose candidates
  // matched near its guess with overlap >= matched_above (see Verify).
  bool lazy_global = true;
  double matched_above = 0.8;
  // The guess-free search for every candidate, whatever its guided overlap
  // (lazy_global and global_below then play no part); the better of the two
  // alignments is kept. In repeated corridors the guided match often settles
  // on a look-alike pose of a right map.
  bool always_global = false;
  double inlier_radius_m = 0.3;   // m, overlap radius
};

struct Alignment {
  Pose2 pose;             // query own frame in db own frame
  double overlap = 0.0;   // fraction of query points within inlier_radius_m after alignment
  double mean_dist_m = 0.5;  // mean distance of the query points to their nearest db point after
                             // alignment (capped at 10 m per point): the ground truth's criterion
  double conflict = 0.0;  // fraction of query points landing in the db map's free space
  double reverse_conflict = 0.0;  // fraction of db points landing in the query map's free space
};

class Verifier {
 public:
  // `maps` (the dataset's db maps) must outlive the verifier.
  Verifier(const std::vector<LocalMap>* maps, const VerifyConfig& config);
  ~Verifier();
  Verifier(const Verifier&) = delete;
  Verifier& operator=(const Verifier&) = delete;

  // A prepared query (opaque).
  class Query;
  std::shared_ptr<const Query> Prepare(const LocalMap& query) const;

  // Aligns the query to each of `dbs` (guesses[i] for dbs[i]) under the
  // config's fallback policy: with lazy_global, first near the guesses only,
  // then guess-free for the poor ones if none reached matched_above.
  // Thread-safe (db maps are prepared once, on first use).
  std::vector<Alignment> Verify(const Query& query, const std::vector<size_t>& dbs,
                                const std::vector<std::vector<Pose2>>& guesses) const;

  // Fraction of `points` (query own frame) that, moved by `pose`, are farther
  // than radius_m from every point of db map `db` AND lie in space the db map
  // observed as free: evidence of a change (not merely an unobserved area).
  double Unexplained(size_t db, const Pose2& pose, const std::vector<Point2>& points, double radius_m) const;

  // Geometric change masks (core/change/geometric_changes.h) of `query`'s
  // points (own frame) against the db maps `aligned` (index, query pose in
  // it) of the query's place; a mask's db_map_id is a db map index.
  std::vector<ChangeMask> Changes(const std::vector<std::pair<size_t, Pose2>>& aligned, const LocalMap& query,
                                  const GeometricChangeOptions& options) const;

  // Frees the prepared db maps.
  void Clear();

 private:
  // Aligns the query to db map `db` near `guesses`, and guess-free when
  // `global` and the guided match is poor (or there are no guesses).
  Alignment Align(const Query& query, size_t db, const std::vector<Pose2>& guesses, bool global) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lmd::eval
