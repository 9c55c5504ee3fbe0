#include "core/align/relative_pose.h"

#include <cmath>

#include <gtest/gtest.h>

#include "core/viewpoint/viewpoint.h"

namespace lmd {
namespace {

Point2 Rotate(double a, Point2 p) { return {std::cos(a) * p.x - std::sin(a) * p.y, std::sin(a) * p.x + std::cos(a) * p.y}; }

// Builds the planned coordinates the index would align and checks that the
// implied pose maps query points onto the same db points.
TEST(RelativePoseTest, MapsQueryPointsOntoTheirDbPositions) {
  const Frame query{{1.0, -2.0}, 0.3};
  const Frame db{{-4.0, 0.5}, 1.1};
  for (int orientation = 0; orientation < 4; ++orientation) {
    const Point2 offset{0.7, -0.2};
    const Pose2 pose = RelativePose(query, db, orientation, offset);
    for (const Point2 p : {Point2{0, 0}, Point2{3, 1}, Point2{-2, 5}}) {
      const Point2 q = ToFrame(query, p);                        // query planned
      const Point2 rq = Rotate(orientation * M_PI / 2, q);
      const Point2 planned_db{rq.x + offset.x, rq.y + offset.y};  // db planned
      const Point2 expected = FromFrame(db, planned_db);          // db own
      const Point2 got = TransformPoint(pose, p);
      EXPECT_NEAR(got.x, expected.x, 1e-9);
      EXPECT_NEAR(got.y, expected.y, 1e-9);
    }
  }
}

TEST(RelativePoseTest, IdenticalFramesGiveIdentity) {
  const Frame frame{{2.0, 3.0}, 0.4};
  const Pose2 pose = RelativePose(frame, frame, 0, {0, 0});
  EXPECT_NEAR(pose.x, 0.0, 1e-12);
  EXPECT_NEAR(pose.y, 0.0, 1e-12);
  EXPECT_NEAR(pose.theta, 0.0, 1e-12);
}

}  // namespace
}  // namespace lmd
