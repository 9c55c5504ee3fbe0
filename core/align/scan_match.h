// Scan matching of two local maps: the pose of the query map's own frame in
// the db map's own frame, and how well the maps then overlap. Used to verify
// retrieval hits geometrically (core/localize/localizer.h) and to refine their pose.
//
//   1. correlative branch-and-bound search (correlative_search.h) on the
//      query points subsampled to search_cell_m, over windows around the
//      guesses (and their quarter turns: planned frames of Manhattan places
//      are ambiguous modulo 90 deg), or, guess-free, over the whole db map
//      with the rotation known modulo 90 deg from the two entropy compasses;
//   2. ICP (icp.h) on the query points subsampled to icp_cell_m, from the
//      best lattice pose;
//   3. score = fraction of query points within inlier_radius_m of a db point
//      (below recheck_below, the lattice pose's score too, and the better kept).
//
// The db side is a PreparedMap (prepared_map.h): build it once per stored map.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "core/align/correlative_search.h"
#include "core/align/icp.h"
#include "core/align/prepared_map.h"
#include "core/types.h"

namespace lmd {

struct ScanMatchOptions {
  PreparedMapOptions map;          // used where this module prepares a db map itself
  double inlier_radius_m = 0.3;    // m; score radius (place-recall protocol: 0.3)
  size_t min_points = 10;          // a query or db map with fewer points is not matched (score 0)
  // A refined pose whose score is below this is compared with the search's
  // lattice pose, and the better kept (1: always compared, as before). 0.5
  // measures the lattice pose only where ICP may have slid off (10 % fewer
  // verification instructions), and keeps ICP's finer pose where the lattice
  // pose overlapped a little more: lmd-eval best's median pose error 0.047 ->
  // 0.033 m (intel, aces, mit, fr079) and 0.034 -> 0.028 m (five other logs).
  double recheck_below = 0.5;
  double search_cell_m = 0.3;      // m; query points kept one per cell for the search (0 = all)
  // m; query points kept one per cell for ICP (0 = all). 0.2 gave lmd-eval's
  // best the same place recall and pose error as all points (orebro, fr101,
  // intel) and cut verification by ~15 % (lmd-microbench); 0.3 (with the
  // looser ICP convergence) cut it by 17 % more at the same place recall@1
  // (0.748 vs 0.748 on intel, aces, mit, fr079; 0.874 vs 0.870 on the five
  // other logs) and median pose error (0.047 vs 0.046 m; 0.034 vs 0.033 m).
  double icp_cell_m = 0.3;
  // Around each guess: the query centroid may move +-window_m per axis and the
  // angle +-window_deg. A retrieval hit's guess already absorbs the planned
  // frames' offset (the kernel's offset); 1 m / 5 deg gave lmd-eval's best
  // the same place recall as 2 m / 10 deg on orebro, fr101 and intel, with
  // 28 % fewer correlative evaluations. 3 deg instead of 5 (the guess's angle
  // comes from two entropy compasses refined to 0.1 deg): lmd-eval best's
  // place recall, pose error and 204 lmdctl answers unchanged on all nine
  // logs, verification 18 % fewer instructions; 2 deg lost 0.003 place@1.
  double window_m = 1.0;
  double window_deg = 3.0;
  bool quarter_turns = true;       // also search each guess turned by 90, 180, 270 deg (about the centroid)
  // Guess-free: rotations h_db - h_query + k global_turn_deg +- global_window_deg,
  // the query centroid anywhere in the db bounding box grown by global_margin_m.
  // 90 = the compasses' ambiguity; 45 also survives a compass off by 45 deg
  // (seen on ~3 % of real pairs) at twice the cost.
  double global_turn_deg = 90.0;
  double global_window_deg = 4.0;
  double global_margin_m = 3.0;
  CorrelativeOptions correlative;
  IcpOptions icp;
};

// The query side, computed once per query and reused for every candidate.
struct PreparedQuery {
  std::vector<Point2> points;         // finite points, own frame (overlap score)
  std::vector<Point2> search_points;  // subsampled to search_cell_m (correlative search)
  std::vector<Point2> icp_points;     // subsampled to icp_cell_m (ICP)
  Point2 centroid;                    // mean of search_points
  double heading = 0.0;               // rad in [0, pi/2), entropy compass
};
// `known_heading`: as for PrepareMap (the query's planned frame heading).
PreparedQuery PrepareQuery(const LocalMap& query, const ScanMatchOptions& options = {},
                           std::optional<double> known_heading = std::nullopt);

struct ScanMatch {
  Pose2 pose;                 // query own frame in db own frame
  double score = 0.0;         // fraction of query points within inlier_radius_m after alignment, [0, 1]
  double inlier_rms_m = 0.0;  // RMS distance of those inliers
  double closeness = 0.0;     // Overlap::closeness (icp.h) at the pose
  size_t inliers = 0;
  double conflict_fraction = 0.0;  // query points in db free space (not inliers) / query points
  double search_score = 0.0;  // mean likelihood at the correlative optimum, [0, 1]
  int guess = -1;             // index of the guess whose window held the optimum; -1 = guess-free
  size_t search_evaluations = 0;  // block scores the search computed (cost measure)
};

// Best pose within the windows around `guesses` (query own frame in db own
// frame). No guesses: same as MatchLocalMapsGlobal. A query or db with fewer
// than min_points points gives score 0 and the first guess (or identity) as
// pose; never fails.
ScanMatch MatchLocalMaps(const PreparedQuery& query, const PreparedMap& db, const std::vector<Pose2>& guesses,
                         const ScanMatchOptions& options = {});
// Convenience: prepares both sides (use the form above to match many pairs).
ScanMatch MatchLocalMaps(const LocalMap& query, const LocalMap& db, const std::vector<Pose2>& guesses,
                         const ScanMatchOptions& options = {});

// Guess-free: the whole db map, rotation from the two maps' dominant
// orientations modulo 90 deg. Slower than a guided match (several times).
ScanMatch MatchLocalMapsGlobal(const PreparedQuery& query, const PreparedMap& db,
                               const ScanMatchOptions& options = {});

// Over the whole db map too, but only at the rotations `thetas` (each
// +- window_deg): the translation is free, the turn known (e.g. a
// retrieval hypothesis's, and its half turn).
ScanMatch MatchLocalMapsAtTurns(const PreparedQuery& query, const PreparedMap& db, const std::vector<double>& thetas,
                                const ScanMatchOptions& options = {});

// The best guess-free alignment at least radius_m (query centroid) or
// angle_deg away from `best`: whether another pose in the same map explains
// the query too (a corridor seen from either end, a repeated bay). Score 0
// when none scores above the search's min_score, or when its refinement
// slides back to within the excluded zone (then it is `best` itself).
ScanMatch SecondBestMatch(const PreparedQuery& query, const PreparedMap& db, const Pose2& best, double radius_m,
                          double angle_deg, const ScanMatchOptions& options = {});

}  // namespace lmd
