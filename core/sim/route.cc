#include "core/sim/route.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/localmap/pose_ops.h"
#include "core/sim/sim_random.h"

namespace lmd {
namespace {

Point2 Project(const Point2& p, const Point2& a, const Point2& b) {
  const double ex = b.x - a.x, ey = b.y - a.y;
  const double len2 = ex * ex + ey * ey;
  const double t = len2 > 0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
  return {a.x + t * ex, a.y + t * ey};
}

// Waypoints of a random walk on the corridor lattice, at least length_m long.
std::vector<Point2> Waypoints(const BuildingLayout& b, const RouteOptions& opt, std::mt19937_64& rng) {
  const int nx = static_cast<int>(b.corridor_x.size()), ny = static_cast<int>(b.corridor_y.size());
  std::vector<Point2> wp;
  if (nx < 1 || ny < 1) return wp;
  const double jitter = std::min(opt.lateral_jitter_m, 0.4 * b.corridor_width);
  auto node_point = [&](int i, int j) {
    return Point2{b.corridor_x[i] + Uniform(rng, -jitter, jitter), b.corridor_y[j] + Uniform(rng, -jitter, jitter)};
  };
  int ci = UniformInt(rng, 0, nx - 1), cj = UniformInt(rng, 0, ny - 1);
  int pi = -1, pj = -1;
  wp.push_back(node_point(ci, cj));
  double length = 0.0;
  auto add = [&](const Point2& p) {
    length += std::hypot(p.x - wp.back().x, p.y - wp.back().y);
    wp.push_back(p);
  };
  const double tol = 1e-6;
  while (length < opt.length_m) {
    int cand_i[4], cand_j[4], n = 0;
    const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
    for (int k = 0; k < 4; ++k) {
      const int ni = ci + di[k], nj = cj + dj[k];
      if (ni < 0 || nj < 0 || ni >= nx || nj >= ny || (ni == pi && nj == pj)) continue;
      cand_i[n] = ni;
      cand_j[n] = nj;
      ++n;
    }
    if (n == 0) {  // dead end (a 1-wide lattice): go back
      if (pi < 0) break;
      cand_i[0] = pi;
      cand_j[0] = pj;
      n = 1;
    }
    const int pick = UniformInt(rng, 0, n - 1);
    const int ni = cand_i[pick], nj = cand_j[pick];
    const Point2 a = wp.back();
    const Point2 goal = node_point(ni, nj);
    // Doors along this corridor stretch, in walking order.
    const double x0 = b.corridor_x[std::min(ci, ni)], x1 = b.corridor_x[std::max(ci, ni)];
    const double y0 = b.corridor_y[std::min(cj, nj)], y1 = b.corridor_y[std::max(cj, nj)];
    std::vector<std::pair<double, const Door*>> doors;
    for (const Door& d : b.doors) {
      const Point2& c = d.corridor_point;
      if (c.x < x0 - tol || c.x > x1 + tol || c.y < y0 - tol || c.y > y1 + tol) continue;
      doors.push_back({std::hypot(c.x - a.x, c.y - a.y), &d});
    }
    std::sort(doors.begin(), doors.end(),
              [](const auto& l, const auto& r) { return l.first < r.first; });
    for (const auto& entry : doors) {
      if (!Chance(rng, opt.room_visit_probability)) continue;
      const Door& d = *entry.second;
      const Point2 q = Project(d.corridor_point, a, goal);
      add(q);
      add(d.door_centre);
      add(d.room_centre);
      add(d.door_centre);
      add(q);
    }
    add(goal);
    pi = ci;
    pj = cj;
    ci = ni;
    cj = nj;
  }
  return wp;
}

}  // namespace

std::vector<Pose2> PlanRoute(const World& world, const RouteOptions& opt) {
  std::vector<Pose2> poses;
  if (opt.building < 0 || static_cast<size_t>(opt.building) >= world.buildings().size()) return poses;
  std::mt19937_64 rng(opt.seed);
  const std::vector<Point2> wp = Waypoints(world.buildings()[static_cast<size_t>(opt.building)], opt, rng);
  if (wp.size() < 2) return poses;
  const double spacing = opt.pose_spacing_m > 0 ? opt.pose_spacing_m : 0.5;
  const double max_turn = opt.max_turn_rad > 0 ? opt.max_turn_rad : 0.35;
  double heading = 0.0;
  bool started = false;
  double travel = 0.0;    // along the waypoint polyline
  double next_at = 0.0;   // travel of the next pose
  for (size_t k = 0; k + 1 < wp.size() && travel <= opt.length_m; ++k) {
    const Point2 a = wp[k], b = wp[k + 1];
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    if (len < 1e-9) continue;
    const double h = std::atan2(b.y - a.y, b.x - a.x);
    if (!started) {
      heading = h;
      started = true;
    } else {
      const double delta = NormalizeAngle(h - heading);
      if (std::abs(delta) > max_turn) {
        const int steps = static_cast<int>(std::ceil(std::abs(delta) / max_turn));
        for (int m = 1; m < steps; ++m) poses.push_back({a.x, a.y, NormalizeAngle(heading + delta * m / steps)});
      }
      heading = h;
    }
    while (next_at <= travel + len + 1e-12 && next_at <= opt.length_m + 1e-9) {
      const double t = (next_at - travel) / len;
      poses.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), h});
      next_at += spacing;
    }
    travel += len;
  }
  return poses;
}

}  // namespace lmd
