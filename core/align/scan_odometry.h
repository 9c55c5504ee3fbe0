// Poses from the scans alone, for recordings without odometry or tf: each
// scan is scan-matched (scan_match.h) against a reference built from the
// last keyframe scans, starting from a constant-velocity guess. Drifts like
// any odometry; where scans overlap little it also fails: on the sparse
// real logs (one scan per 0.5-1 m or 30 deg) the pose error over a 5 m local
// map is 5-15 cm in the median, but 0.2-6.8 m at the 90th percentile
// (docs/bags.md).
#pragma once

#include <cstddef>
#include <vector>

#include "core/align/scan_match.h"
#include "core/types.h"

namespace lmd {

struct ScanOdometryOptions {
  // A scan this far (m) or this much turned (deg) from the last keyframe becomes one.
  double keyframe_distance_m = 0.3;
  double keyframe_angle_deg = 10.0;
  size_t reference_keyframes = 8;  // the reference map holds the last this many keyframes' points
  double point_cell_m = 0.05;      // m; a scan's endpoints kept one per cell
  // A match scoring below this (fraction of the scan's points within
  // inlier_radius_m of the reference) is not trusted: the guess is kept.
  double min_score = 0.3;
  // Searched: +-window_m and +-window_deg around the constant-velocity guess
  // and around the guess turned by multiples of 2 window_deg up to
  // max_turn_deg (intel's log, one scan per 0.5-1 m or 30 deg turned, turns
  // by up to 36 deg between scans); a turned match wins only if it scores
  // higher. On intel, 10 deg windows with every turned guess gave a 5 m pose
  // error of 0.072 m median, 0.27 m p90; 20 deg windows with turned guesses
  // only after a match below 0.7, 0.14 m and 2.0 m.
  double window_m = 1.0;
  double window_deg = 10.0;
  double max_turn_deg = 60.0;
};

struct ScanOdometry {
  std::vector<Pose2> poses;  // one per scan: laser pose, the first scan at (0, 0, 0)
  size_t weak_matches = 0;   // scans whose match scored below min_score (pose = guess)
  double mean_score = 0.0;   // mean match score over the scans after the first
};

// Laser poses of `scans` (their own poses are ignored), in the first scan's frame.
ScanOdometry EstimateScanOdometry(const std::vector<Scan>& scans, const ScanOdometryOptions& options = {});

}  // namespace lmd
