#include "proto/convert.h"

namespace lmd {

Pose2 FromProto(const v1::Pose2& pose) { return {pose.x(), pose.y(), pose.theta()}; }

v1::Pose2 ToProto(const Pose2& pose) {
  v1::Pose2 out;
  out.set_x(pose.x);
  out.set_y(pose.y);
  out.set_theta(pose.theta);
  return out;
}

v1::PoseCovariance ToProto(const Eigen::Matrix3d& covariance) {
  v1::PoseCovariance out;
  out.set_xx(covariance(0, 0));
  out.set_xy(covariance(0, 1));
  out.set_xt(covariance(0, 2));
  out.set_yy(covariance(1, 1));
  out.set_yt(covariance(1, 2));
  out.set_tt(covariance(2, 2));
  return out;
}

Eigen::Matrix3d FromProto(const v1::PoseCovariance& covariance) {
  Eigen::Matrix3d out;
  out << covariance.xx(), covariance.xy(), covariance.xt(),  //
      covariance.xy(), covariance.yy(), covariance.yt(),     //
      covariance.xt(), covariance.yt(), covariance.tt();
  return out;
}

LocalMap FromProto(const v1::LocalMap& map) {
  LocalMap out;
  out.points.resize(map.x_size());
  for (int i = 0; i < map.x_size(); ++i) out.points[i] = {map.x(i), map.y(i)};
  out.trajectory.reserve(map.trajectory_size());
  for (const auto& pose : map.trajectory()) out.trajectory.push_back(FromProto(pose));
  out.scans.reserve(map.scans_size());
  for (const auto& scan : map.scans()) {
    Scan s;
    s.pose = FromProto(scan.pose());
    s.first_angle = scan.first_angle();
    s.angle_step = scan.angle_step();
    s.max_range = scan.max_range();
    s.ranges.assign(scan.ranges().begin(), scan.ranges().end());
    out.scans.push_back(std::move(s));
  }
  out.heading_drift_rad_per_m = map.heading_drift_rad_per_m();
  return out;
}

v1::LocalMap ToProto(const LocalMap& map) {
  v1::LocalMap out;
  out.mutable_x()->Reserve(static_cast<int>(map.points.size()));
  out.mutable_y()->Reserve(static_cast<int>(map.points.size()));
  for (const Point2& p : map.points) {
    out.add_x(static_cast<float>(p.x));
    out.add_y(static_cast<float>(p.y));
  }
  for (const Pose2& pose : map.trajectory) *out.add_trajectory() = ToProto(pose);
  for (const Scan& scan : map.scans) {
    v1::Scan* s = out.add_scans();
    *s->mutable_pose() = ToProto(scan.pose);
    s->set_first_angle(scan.first_angle);
    s->set_angle_step(scan.angle_step);
    s->set_max_range(scan.max_range);
    s->mutable_ranges()->Add(scan.ranges.begin(), scan.ranges.end());
  }
  out.set_heading_drift_rad_per_m(map.heading_drift_rad_per_m);
  return out;
}

}  // namespace lmd
