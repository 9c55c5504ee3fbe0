// Local refinement of a query-to-db pose (ICP), how closely that fit
// determines the pose (its covariance), and the overlap score that
// verification ranks by. Point-to-line residuals where the db point has a
// normal (walls), point-to-point elsewhere, plus a small point-to-point term
// everywhere so corridors (one normal direction) stay well-posed; Huber
// weights; Gauss-Newton on (x, y, theta) with Eigen.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "core/align/prepared_map.h"
#include "core/types.h"

namespace lmd {

struct IcpOptions {
  int max_iterations = 20;            // Gauss-Newton iterations (each re-finds correspondences)
  double max_correspondence_m = 0.4;  // m; farther pairs are ignored (<= db neighbour_cell_m)
  double huber_m = 0.1;               // m; residuals beyond are down-weighted
  double point_to_point_weight = 0.1; // weight of the point-to-point term on line points
  // m (and rad); stop when a step is smaller. 1e-3 instead of 1e-4: 5.7
  // instead of 7.9 iterations per refinement (lmd-bench load), lmd-eval
  // best's place recall and pose error unchanged (intel, aces, mit, fr079;
  // 358 queries, seed 5).
  double converged_m = 1e-3;
};

// ICP from `initial` (query own frame in db own frame). Returns `initial`
// when fewer than 3 correspondences exist or the system is singular.
Pose2 RefinePose(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& initial,
                 const IcpOptions& options = {});

// How well the fit at a pose determines it, as a robot fusing the answer
// needs it. Calibrated on the tuning logs (aces, fr079, intel, orebro;
// lmd-eval served --mode tracking, 2026-12-07, docs/results.md): with the
// floor below, 3 is the smallest whole scale that puts the true pose of 95 %
// of their sure answers within the 95 % ellipsoid (mean over those logs
// 0.956; 2 gave 0.949). Held out: 0.936, edmonton's 0.83 the least (its
// truth is the loosest: 7 cm median error of right top hits).
struct PoseCovarianceOptions {
  // The formal covariance of a least-squares fit (residual variance times
  // the inverse information) takes every point for an independent
  // measurement; a map's points are not (a wall is off as a whole), so the
  // standard deviations are scaled by this.
  double scale = 3.0;
  double min_residual_m = 0.01;  // a residual's standard deviation is taken as at least this
  // A weak prior: the pose lies within the search's reach (a map that
  // constrains no direction leaves this).
  double max_sigma_m = 1.0, max_sigma_rad = 0.1;
  // Added whatever the fit: two maps of one place, each built from its own
  // pass, differ by about this (the median error of right top hits is 2-3
  // cm and 0.1-0.2 deg on the logs), however many walls pin the fit.
  double floor_sigma_m = 0.03, floor_sigma_rad = 0.3 * M_PI / 180;
};

// Covariance of `pose` (query own frame in db own frame; x, y in m, theta in
// rad) from the point-to-line fit there, its correspondences and Huber
// weights as ICP with `icp` finds them: a direction the map's walls do not
// constrain (along a corridor) keeps a large variance, one many walls cross
// a small one. The point-to-point terms ICP adds on walls are left out:
// they pin a point along its wall by correspondences, not by evidence.
Eigen::Matrix3d PoseCovariance(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& pose,
                               const IcpOptions& icp = {}, const PoseCovarianceOptions& options = {});

// What a fit of `query` on `db` cannot know of the pose because either map
// bends (PreparedMap::bend): both maps' heading and position variances,
// summed (the position's alike in every direction). Zero for rigid maps.
Eigen::Matrix3d BendCovariance(const PreparedMap& query, const PreparedMap& db);

// The standard deviations a pose covariance (x, y in m, theta in rad)
// gives: the position's along its least known direction (the larger
// eigenvalue of the x-y block) and the heading's; infinite for a covariance
// that is not finite.
struct PoseDeviations {
  double position_m = 0.0, heading_rad = 0.0;
};
PoseDeviations PoseStandardDeviations(const Eigen::Matrix3d& covariance);

struct Overlap {
  double fraction = 0.0;  // inliers / query points; 0 for an empty query or db
  double rms_m = 0.0;     // RMS distance of the inliers to their nearest db point
  // Mean over the query points of a credit that falls with the distance to
  // the nearest db point: 1 within a third of the radius, 2/3 within two
  // thirds, 1/3 within the radius, else 0. Two poses that bring as many
  // points within the radius differ here by how closely they do.
  double closeness = 0.0;
  size_t inliers = 0;     // query points within the radius of a db point
  // Outliers that land in cells the db map saw as free (a wall where the db
  // map saw through): evidence against the alignment. 0 without free space.
  size_t conflicts = 0;
  double conflict_fraction = 0.0;  // conflicts / query points
};

// Overlap of the query points moved by `pose` with the db points, radius_m
// (<= db neighbour_cell_m).
Overlap MeasureOverlap(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& pose,
                       double radius_m);

}  // namespace lmd
