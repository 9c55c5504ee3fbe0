// Local maps from a laser log (DESIGN.md §1, the paper's protocol): one map
// per length_m of travel, a new one started every step_m of travel.
#pragma once

#include <string>
#include <vector>

#include "core/io/laser_log.h"
#include "core/types.h"

namespace lmd {

struct LocalMapOptions {
  double length_m = 5.0;      // m of travel covered by one map (paper: 5)
  double step_m = 1.0;        // m of travel between map starts (paper: 1)
  double dedup_cell_m = 0.1;  // m; one point kept per cell of this grid
  std::string id_prefix;      // map id = "<id_prefix>-<k>", or "<k>" if empty
  bool keep_scans = true;     // copy the scans (own frame) into each map
  // Stated on every map (LocalMap::heading_drift_rad_per_m): how far the
  // log's poses may turn per metre from the truth (0: scan-matched or SLAM
  // poses, rigid maps; wheel odometry's bound otherwise).
  double heading_drift_rad_per_m = 0.0;
};

// Travel = cumulative distance between consecutive scan positions. Map k
// covers the scans whose travel lies in [k*step_m, k*step_m + length_m]; it is
// emitted only if the log reaches k*step_m + length_m (no partial last map)
// and it holds at least one scan not starting the previous map (gaps in a log
// do not duplicate maps). Each map is in its own frame = the pose of its first
// scan (so trajectory[0] is (0, 0, 0)); points = scan endpoints with range in
// [0, max_range), deduplicated on a dedup_cell_m grid (first endpoint kept);
// truth.global_frame = first pose in the log frame, truth.travel_start /
// travel_end = travel at its first / last scan. Empty if the log is shorter
// than length_m.
std::vector<LocalMap> BuildLocalMaps(const LaserLog& log, const LocalMapOptions& options = {});

// Endpoints of the beams with a return (range < max_range), in the scans'
// frame, one per dedup_cell_m cell (the first one met, in scan/beam order).
std::vector<Point2> PointsFromScans(const std::vector<Scan>& scans, double dedup_cell_m = 0.1);

// `points` with one kept per dedup_cell_m cell (the first met, order kept),
// as BuildLocalMaps keeps them; points of maps it built all stay.
std::vector<Point2> DeduplicatePoints(const std::vector<Point2>& points, double dedup_cell_m = 0.1);

// Cumulative travel (m) at each scan of the log: 0 at the first scan.
std::vector<double> CumulativeTravel(const LaserLog& log);

}  // namespace lmd
