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
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    int pairs = 0;
    // Adds residual r = a . (q - d) with Jacobian a^T [I | dq/dtheta], weight w.
    auto add = [&](const Eigen::Vector2d& a, double r, const Eigen::Vector2d& dq_dtheta, double w) {
      const Eigen::Vector3d J(a.x(), a.y(), a.dot(dq_dtheta));
      H += w * J * J.transpose();
      g += w * J * r;
    };
    for (const Point2& p : query_points) {
      const Point2 q{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
      double d2 = 0;
      const int j = NearestPoint(db, q, max_dist, &d2);
      if (j < 0) continue;
      ++pairs;
      const Eigen::Vector2d e(q.x - db.points[j].x, q.y - db.points[j].y);
      const Eigen::Vector2d dq(-(q.y - pose.y), q.x - pose.x);
      const Point2 n = db.normals[j];
      const bool line = n.x != 0.0 || n.y != 0.0;
      const double dist = line ? std::abs(n.x * e.x() + n.y * e.y()) : std::sqrt(d2);
      const double w = dist <= options.huber_m ? 1.0 : options.huber_m / dist;
      const double wp = line ? w * wpp : w;
      if (line) {
        const Eigen::Vector2d nn(n.x, n.y);
        add(nn, nn.dot(e), dq, w);
      }
      if (wp > 0) {
        add(Eigen::Vector2d(1, 0), e.x(), dq, wp);
        add(Eigen::Vector2d(0, 1), e.y(), dq, wp);
      }
    }
    if (pairs < 3) break;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
    if (ldlt.info() != Eigen::Success) break;
    const Eigen::Vector3d delta = ldlt.solve(-g);
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
  for (const Point2& p : query_points) {
    const Point2 q{pose.x + c * p.x - s * p.y, pose.y + s * p.x + c * p.y};
    double d2 = 0;
    if (NearestPoint(db, q, radius_m, &d2) >= 0) {
      ++o.inliers;
      sum2 += d2;
    } else if (InFreeSpace(db, q)) {
      ++o.conflicts;
    }
  }
  o.fraction = static_cast<double>(o.inliers) / query_points.size();
  o.conflict_fraction = static_cast<double>(o.conflicts) / query_points.size();
  o.rms_m = o.inliers ? std::sqrt(sum2 / o.inliers) : 0.0;
  return o;
}

}  // namespace lmd
