// Test fixture for grid / viewpoint / describer tests (Helper B): a tiny
// wall-segment world with its own ray caster, so those tests do not depend on
// the simulator. Header-only.
#pragma once

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "core/types.h"

namespace lmd::testing {

struct Wall {
  Point2 a, b;
};

// A 6 m x 6 m room [0, 6] x [0, 6] with a 1 m door in its east wall (y in
// [2.5, 3.5]) onto a 2 m wide corridor running north-south at x in [6, 8],
// from y = -6 to y = 12.
inline std::vector<Wall> RoomAndCorridor() {
  return {
      {{0, 0}, {6, 0}}, {{0, 6}, {6, 6}}, {{0, 0}, {0, 6}},               // room S, N, W
      {{6, 0}, {6, 2.5}}, {{6, 3.5}, {6, 6}},                             // room E with door
      {{6, -6}, {6, 0}}, {{6, 6}, {6, 12}}, {{8, -6}, {8, 12}},           // corridor sides
      {{6, -6}, {8, -6}}, {{6, 12}, {8, 12}},                             // corridor ends
  };
}

// Distance along the ray from o at angle a to the first wall, or max_range.
inline double CastRay(const std::vector<Wall>& walls, const Point2& o, double a, double max_range) {
  const double dx = std::cos(a), dy = std::sin(a);
  double best = max_range;
  for (const Wall& w : walls) {
    const double ex = w.b.x - w.a.x, ey = w.b.y - w.a.y;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;
    const double wx = w.a.x - o.x, wy = w.a.y - o.y;
    const double t = (wx * ey - wy * ex) / den;  // along the ray
    const double u = (wx * dy - wy * dx) / den;  // along the wall
    if (t > 1e-9 && u >= 0 && u <= 1) best = std::min(best, t);
  }
  return best;
}

// A local map in the world frame: scans (181 beams over 180 deg) from each
// pose, points = returns deduplicated on a 0.1 m grid.
inline LocalMap ScanWorld(const std::vector<Wall>& walls, const std::vector<Pose2>& poses, double max_range = 20.0) {
  LocalMap map;
  map.trajectory = poses;
  std::set<std::pair<long, long>> seen;
  for (const Pose2& p : poses) {
    Scan s;
    s.pose = p;
    s.first_angle = static_cast<float>(-M_PI / 2);
    s.angle_step = static_cast<float>(M_PI / 180);
    s.max_range = static_cast<float>(max_range);
    for (int i = 0; i <= 180; ++i) {
      const double a = p.theta + s.first_angle + i * s.angle_step;
      const double r = CastRay(walls, {p.x, p.y}, a, max_range);
      s.ranges.push_back(static_cast<float>(r));
      if (r >= max_range) continue;
      const Point2 e{p.x + r * std::cos(a), p.y + r * std::sin(a)};
      const std::pair<long, long> key{std::lround(std::floor(e.x / 0.1)), std::lround(std::floor(e.y / 0.1))};
      if (!seen.insert(key).second) continue;
      map.points.push_back(e);
    }
    map.scans.push_back(std::move(s));
  }
  return map;
}

// The robot walks through the room: from the corridor through the door to
// the room centre, turning around.
inline std::vector<Pose2> RoomVisit() {
  std::vector<Pose2> poses;
  for (double y = -2; y <= 3; y += 0.5) poses.push_back({7, y, M_PI / 2});
  for (double x = 7; x >= 2.5; x -= 0.5) poses.push_back({x, 3, M_PI});
  for (double t = M_PI; t <= 3 * M_PI; t += M_PI / 6) poses.push_back({2.5, 3, t});
  return poses;
}

// map with every pose and point moved by the rigid transform t (t * p).
inline LocalMap Transformed(const LocalMap& map, const Pose2& t) {
  const double c = std::cos(t.theta), s = std::sin(t.theta);
  auto tp = [&](const Point2& p) { return Point2{t.x + c * p.x - s * p.y, t.y + s * p.x + c * p.y}; };
  LocalMap out = map;
  for (Point2& p : out.points) p = tp(p);
  for (Pose2& p : out.trajectory) {
    const Point2 q = tp({p.x, p.y});
    p = {q.x, q.y, p.theta + t.theta};
  }
  for (Scan& sc : out.scans) {
    const Point2 q = tp({sc.pose.x, sc.pose.y});
    sc.pose = {q.x, q.y, sc.pose.theta + t.theta};
  }
  return out;
}

}  // namespace lmd::testing
