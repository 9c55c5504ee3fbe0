#include "core/align/scan_odometry.h"

#include <cmath>
#include <deque>

#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

ScanOdometry EstimateScanOdometry(const std::vector<Scan>& scans, const ScanOdometryOptions& options) {
  ScanOdometry out;
  if (scans.empty()) return out;
  ScanMatchOptions match;
  match.window_m = options.window_m;
  match.window_deg = options.window_deg;
  match.quarter_turns = false;

  // A scan's endpoints in its own laser frame.
  auto own_points = [&](const Scan& s) {
    Scan at_origin = s;
    at_origin.pose = Pose2{};
    return PointsFromScans({at_origin}, options.point_cell_m);
  };
  std::deque<std::vector<Point2>> keyframes;  // world-frame points of the last keyframes
  PreparedMap reference;
  auto add_keyframe = [&](const Scan& s, const Pose2& pose) {
    std::vector<Point2> world;
    for (const Point2& p : own_points(s)) world.push_back(TransformPoint(pose, p));
    keyframes.push_back(std::move(world));
    while (keyframes.size() > options.reference_keyframes) keyframes.pop_front();
    LocalMap ref;
    for (const auto& k : keyframes) ref.points.insert(ref.points.end(), k.begin(), k.end());
    ref.points = DeduplicatePoints(ref.points, options.point_cell_m);
    reference = PrepareMap(ref, match.map);
  };

  out.poses.push_back(Pose2{});
  add_keyframe(scans[0], out.poses[0]);
  Pose2 keyframe_pose = out.poses[0];
  Pose2 velocity{};  // last relative motion
  double score_sum = 0;
  for (size_t i = 1; i < scans.size(); ++i) {
    const Pose2& last = out.poses.back();
    const Pose2 guess = Compose(last, velocity);
    LocalMap query;
    query.points = own_points(scans[i]);
    Pose2 pose = guess;
    // Around the guess, then around the guess turned by multiples of the
    // window up to max_turn_deg (not beyond: in a corridor the scan turned by
    // 180 deg fits as well); a turned match wins only if it scores higher.
    const PreparedQuery prepared = PrepareQuery(query, match);
    ScanMatch m = MatchLocalMaps(prepared, reference, {guess}, match);
    std::vector<Pose2> turned;
    const double step = 2 * options.window_deg * M_PI / 180;
    for (int k = 1; (k - 0.5) * step < options.max_turn_deg * M_PI / 180; ++k) {
      turned.push_back({guess.x, guess.y, guess.theta + k * step});
      turned.push_back({guess.x, guess.y, guess.theta - k * step});
    }
    if (!turned.empty()) {
      const ScanMatch wide = MatchLocalMaps(prepared, reference, turned, match);
      if (wide.score > m.score) m = wide;
    }
    if (m.score >= options.min_score) {
      pose = m.pose;
    } else {
      ++out.weak_matches;
    }
    score_sum += m.score;
    velocity = Compose(Inverse(last), pose);
    out.poses.push_back(pose);
    const Pose2 since = Compose(Inverse(keyframe_pose), pose);
    if (std::hypot(since.x, since.y) >= options.keyframe_distance_m ||
        std::abs(since.theta) >= options.keyframe_angle_deg * M_PI / 180) {
      add_keyframe(scans[i], pose);
      keyframe_pose = pose;
    }
  }
  out.mean_score = score_sum / static_cast<double>(scans.size() - 1);
  return out;
}

}  // namespace lmd
