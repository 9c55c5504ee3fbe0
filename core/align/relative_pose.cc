#include "core/align/relative_pose.h"

#include <cmath>

namespace lmd {
namespace {

Point2 Rotate(double angle, const Point2& p) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * p.x - s * p.y, s * p.x + c * p.y};
}

}  // namespace

Pose2 RelativePose(const Frame& query_frame, const Frame& db_frame, int orientation, const Point2& offset) {
  const double theta = db_frame.heading + orientation * (M_PI / 2) - query_frame.heading;
  const Point2 offset_own = Rotate(db_frame.heading, offset);
  const Point2 query_origin = Rotate(theta, query_frame.origin);
  Pose2 pose;
  pose.x = db_frame.origin.x + offset_own.x - query_origin.x;
  pose.y = db_frame.origin.y + offset_own.y - query_origin.y;
  pose.theta = std::remainder(theta, 2 * M_PI);
  return pose;
}

}  // namespace lmd
