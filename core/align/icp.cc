#include "core/align/icp.h"

#include <cmath>

#include <Eigen/Dense>

namespace lmd {

Pose2 RefinePose(const std::vector<Point2>& query_points, const PreparedMap& db, const Pose2& initial,
                 const IcpOptions& options) {
  Pose2 pose = initial;
  if (query_points.empty() || db.empty()) return pose;
  const double max_dist = std::min(options.max_correspondence_m, db.options.neighbour_cell_m);
  const double wpp = std::max(0.0, options.point_to_point_weight);
  for (int it = 0; it < options.max_iterations; ++it) {
    const double c = std::cos(pose.theta), s = std::sin(pose.theta);
    // Normal equations H delta = -g, accumulated as scalars (H symmetric).
    double h00 = 0, h01 = 0, h02 = 0, h11 = 0, h12 = 0, h22 = 0, g0 = 0, g1 = 0, g2 = 0;
    int pairs = 0;
    // Adds residual r = a . (q - d) with Jacobian a^T [I | dq/dtheta], weight w.
    auto add = [&](double ax, double ay, double r, double dqx, double dqy, double w) {
      const double at = ax * dqx + ay * dqy;
      const double wx = w * ax, wy = w * ay, wt = w * at;
      h00 += wx * ax; h01 += wx * ay; h02 += wx * at;
      h11 += wy * ay; h12 += wy * at; h22 += wt * at;
      g0 += wx * r; g1 += wy * r; g2 += wt * r;
    };
    for (const Point2& p : query_points) {
      const Point2 q{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
      double d2 = 0;
      const int j = NearestPoint(db, q, max_dist, &d2);
      if (j < 0) continue;
      ++pairs;
      const double ex = q.x - db.points[j].x, ey = q.y - db.points[j].y;
      const double dqx = -(q.y - pose.y), dqy = q.x - pose.x;
      const Point2 n = db.normals[j];
      const bool line = n.x != 0.0 || n.y != 0.0;
      const double dist = line ? std::abs(n.x * ex + n.y * ey) : std::sqrt(d2);
      const double w = dist <= options.huber_m ? 1.0 : options.huber_m / dist;
      const double wp = line ? w * wpp : w;
      if (line) add(n.x, n.y, n.x * ex + n.y * ey, dqx, dqy, w);
      if (wp > 0) {
        add(1, 0, ex, dqx, dqy, wp);
        add(0, 1, ey, dqx, dqy, wp);
      }
    }
    if (pairs < 3) break;
    Eigen::Matrix3d H;
    H << h00, h01, h02, h01, h11, h12, h02, h12, h22;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    if (ldlt.info() != Eigen::Success) break;
    const Eigen::Vector3d delta = ldlt.solve(-Eigen::Vector3d(g0, g1, g2));
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
