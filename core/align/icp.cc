#include "core/align/icp.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

namespace lmd {

namespace {

// The Gauss-Newton normal equations of the fit at `pose`: H delta = -g,
// accumulated as scalars (H symmetric), and the weighted squared
// point-to-line residuals.
struct NormalEquations {
  double h00 = 0, h01 = 0, h02 = 0, h11 = 0, h12 = 0, h22 = 0, g0 = 0, g1 = 0, g2 = 0;
  int pairs = 0;
  double line_weight = 0, line_residual2 = 0;  // sums of w and w r^2 over the point-to-line terms
  Eigen::Matrix3d H() const {
    Eigen::Matrix3d h;
    h << h00, h01, h02, h01, h11, h12, h02, h12, h22;
    return h;
  }
};

NormalEquations Accumulate(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& pose,
                           const IcpOptions& options) {
  NormalEquations e;
  const double max_dist = std::min(options.max_correspondence_m, db.options.neighbour_cell_m);
  const double wpp = std::max(0.0, options.point_to_point_weight);
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  // Adds residual r = a . (q - d) with Jacobian a^T [I | dq/dtheta], weight w.
  auto add = [&](double ax, double ay, double r, double dqx, double dqy, double w) {
    const double at = ax * dqx + ay * dqy;
    const double wx = w * ax, wy = w * ay, wt = w * at;
    e.h00 += wx * ax; e.h01 += wx * ay; e.h02 += wx * at;
    e.h11 += wy * ay; e.h12 += wy * at; e.h22 += wt * at;
    e.g0 += wx * r; e.g1 += wy * r; e.g2 += wt * r;
  };
  for (const Point2& p : query_points) {
    const Point2 q{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
    double d2 = 0;
    const int j = NearestPoint(db, q, max_dist, &d2);
    if (j < 0) continue;
    ++e.pairs;
    const double ex = q.x - db.points[j].x, ey = q.y - db.points[j].y;
    const double dqx = -(q.y - pose.y), dqy = q.x - pose.x;
    const Point2 n = db.normals[j];
    const bool line = n.x != 0.0 || n.y != 0.0;
    const double dist = line ? std::abs(n.x * ex + n.y * ey) : std::sqrt(d2);
    const double w = dist <= options.huber_m ? 1.0 : options.huber_m / dist;
    const double wp = line ? w * wpp : w;
    if (line) {
      add(n.x, n.y, n.x * ex + n.y * ey, dqx, dqy, w);
      e.line_weight += w;
      e.line_residual2 += w * dist * dist;
    }
    if (wp > 0) {
      add(1, 0, ex, dqx, dqy, wp);
      add(0, 1, ey, dqx, dqy, wp);
    }
  }
  return e;
}

}  // namespace

Pose2 RefinePose(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& initial,
                 const IcpOptions& options) {
  Pose2 pose = initial;
  if (query_points.empty() || db.empty()) return pose;
  for (int it = 0; it < options.max_iterations; ++it) {
    const NormalEquations e = Accumulate(query_points, db, pose, options);
    if (e.pairs < 3) break;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(e.H());
    if (ldlt.info() != Eigen::Success) break;
    const Eigen::Vector3d delta = ldlt.solve(-Eigen::Vector3d(e.g0, e.g1, e.g2));
    if (!delta.allFinite()) break;
    pose.x += delta.x();
    pose.y += delta.y();
    pose.theta = std::remainder(pose.theta + delta.z(), 2.0 * M_PI);
    if (std::abs(delta.x()) < options.converged_m && std::abs(delta.y()) < options.converged_m &&
        std::abs(delta.z()) < options.converged_m) {
      break;
    }
  }
  return pose;
}

Eigen::Matrix3d BendCovariance(const PreparedMap& query, const PreparedMap& db) {
  const auto squared = [](double sd) { return sd * sd; };
  const double position = squared(query.bend.position_sd_m) + squared(db.bend.position_sd_m);
  const double heading = squared(query.bend.heading_sd_rad) + squared(db.bend.heading_sd_rad);
  return Eigen::Vector3d(position, position, heading).asDiagonal();
}

PoseDeviations PoseStandardDeviations(const Eigen::Matrix3d& covariance) {
  if (!covariance.allFinite()) {
    const double unknown = std::numeric_limits<double>::infinity();
    return {unknown, unknown};
  }
  const double half_sum = (covariance(0, 0) + covariance(1, 1)) / 2;
  const double half_diff = (covariance(0, 0) - covariance(1, 1)) / 2;
  const double largest = half_sum + std::hypot(half_diff, covariance(0, 1));  // of the 2 x 2 block, symmetric
  return {std::sqrt(std::max(0.0, largest)), std::sqrt(std::max(0.0, covariance(2, 2)))};
}

Eigen::Matrix3d PoseCovariance(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& pose,
                               const IcpOptions& icp, const PoseCovarianceOptions& options) {
  const Eigen::Vector3d bound(options.max_sigma_m, options.max_sigma_m, options.max_sigma_rad);
  Eigen::Matrix3d covariance = bound.cwiseProduct(bound).asDiagonal();
  if (query_points.empty() || db.empty()) return covariance;
  IcpOptions fit = icp;
  fit.point_to_point_weight = 0.0;  // it pins a wall's points along the wall: no evidence of where they lie
  const NormalEquations e = Accumulate(query_points, db, pose, fit);
  if (e.pairs < 3 || e.line_weight <= 0) return covariance;
  // Each residual's variance: the fit's own, at least min_residual_m.
  const double variance = std::max(e.line_residual2 / e.line_weight, options.min_residual_m * options.min_residual_m);
  const double scale2 = options.scale * options.scale;
  // The information of the fit, plus that of `bound` (the pose is within the
  // search's reach whatever the fit says): a direction no wall constrains
  // keeps the bound's variance.
  const Eigen::Matrix3d information = e.H() / (scale2 * variance) + covariance.inverse();
  const Eigen::Matrix3d inverse = information.inverse();
  if (!inverse.allFinite()) return covariance;
  const Eigen::Vector3d floor(options.floor_sigma_m, options.floor_sigma_m, options.floor_sigma_rad);
  return inverse + Eigen::Matrix3d(floor.cwiseProduct(floor).asDiagonal());
}

Overlap MeasureOverlap(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& pose,
                       double radius_m) {
  Overlap o;
  if (query_points.empty() || db.empty()) return o;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  double sum2 = 0.0;
  size_t credit = 0;  // thirds
  const double third2 = radius_m * radius_m / 9;
  for (const Point2& p : query_points) {
    const Point2 q{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
    double d2 = 0;
    if (NearestPoint(db, q, radius_m, &d2) >= 0) {
      ++o.inliers;
      sum2 += d2;
      credit += d2 <= third2 ? 3 : d2 <= 4 * third2 ? 2 : 1;
    } else if (InFreeSpace(db, q)) {
      ++o.conflicts;
    }
  }
  o.fraction = static_cast<double>(o.inliers) / query_points.size();
  o.closeness = static_cast<double>(credit) / (3.0 * query_points.size());
  o.conflict_fraction = static_cast<double>(o.conflicts) / query_points.size();
  o.rms_m = o.inliers ? std::sqrt(sum2 / o.inliers) : 0.0;
  return o;
}

}  // namespace lmd
