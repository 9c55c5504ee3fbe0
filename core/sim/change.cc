#include "core/sim/change.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/cell_set.h"
#include "core/localmap/local_map_builder.h"
#include "core/sim/sim_random.h"

namespace lmd {
namespace {

struct Box2 {
  double x0, y0, x1, y1;
  bool Contains(const Point2& p) const { return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1; }
};

void AddRect(double x0, double y0, double x1, double y1, std::vector<Segment>* walls) {
  walls->push_back({{x0, y0}, {x1, y0}});
  walls->push_back({{x1, y0}, {x1, y1}});
  walls->push_back({{x1, y1}, {x0, y1}});
  walls->push_back({{x0, y1}, {x0, y0}});
}

}  // namespace

Result<SimulatedChange> ApplySimulatedChange(LocalMap& map, std::mt19937_64& rng, const ChangeOptions& opt) {
  size_t beams = 0;
  for (const Scan& s : map.scans) beams += s.ranges.size();
  if (beams == 0) return Status::InvalidArgument("map '" + map.id + "' has no scans: cannot simulate a change");
  const double lo_side = std::max(0.05, opt.min_side_m), hi_side = std::max(lo_side, opt.max_side_m);
  std::vector<float> new_ranges;
  std::vector<uint8_t> hit;
  for (int attempt = 0; attempt < opt.max_attempts; ++attempt) {
    // A free point the laser saw: along a random beam, before its return.
    const Scan& scan = map.scans[rng() % map.scans.size()];
    if (scan.ranges.empty()) continue;
    const size_t beam = rng() % scan.ranges.size();
    const double r = std::min<double>(scan.ranges[beam], scan.max_range);
    const double far = std::min(r, opt.max_place_range_m) - 0.3;
    const double near = 0.5;
    if (far <= near) continue;
    const double t = Uniform(rng, near, far);
    const double a = scan.pose.theta + scan.first_angle + static_cast<double>(beam) * scan.angle_step;
    const Point2 c{scan.pose.x + t * std::cos(a), scan.pose.y + t * std::sin(a)};
    const double w = Uniform(rng, lo_side, hi_side), h = Uniform(rng, lo_side, hi_side);
    const Box2 region{c.x - w / 2, c.y - h / 2, c.x + w / 2, c.y + h / 2};
    const double m = opt.robot_clearance_m;
    const Box2 keep_out{region.x0 - m, region.y0 - m, region.x1 + m, region.y1 + m};
    bool blocked = false;
    for (const Scan& s : map.scans) blocked = blocked || keep_out.Contains({s.pose.x, s.pose.y});
    for (const Pose2& p : map.trajectory) blocked = blocked || keep_out.Contains({p.x, p.y});
    if (blocked) continue;

    // Objects: small axis-aligned rectangles inside the region.
    std::vector<Segment> objects;
    const int n = UniformInt(rng, std::max(1, opt.min_objects), std::max(std::max(1, opt.min_objects), opt.max_objects));
    for (int k = 0; k < n; ++k) {
      // Strictly inside (1 cm margin) so that every object return lies in the region.
      const double sx = Uniform(rng, std::min(opt.min_object_m, w - 0.03), std::min(opt.max_object_m, w - 0.03));
      const double sy = Uniform(rng, std::min(opt.min_object_m, h - 0.03), std::min(opt.max_object_m, h - 0.03));
      const double x0 = Uniform(rng, region.x0 + 0.01, region.x1 - 0.01 - sx);
      const double y0 = Uniform(rng, region.y0 + 0.01, region.y1 - 0.01 - sy);
      AddRect(x0, y0, x0 + sx, y0 + sy, &objects);
    }
    const World world(objects, {}, 0.25);

    // Re-ray-cast every beam against the objects.
    new_ranges.clear();
    hit.clear();
    size_t hits = 0;
    for (const Scan& s : map.scans) {
      for (size_t i = 0; i < s.ranges.size(); ++i) {
        const double old_r = std::min<double>(s.ranges[i], s.max_range);
        const double ang = s.pose.theta + s.first_angle + static_cast<double>(i) * s.angle_step;
        const double nr = world.CastRay({s.pose.x, s.pose.y}, ang, old_r);
        const bool h_ = nr < old_r;
        new_ranges.push_back(h_ ? static_cast<float>(nr) : s.ranges[i]);
        hit.push_back(h_ ? 1 : 0);
        hits += h_ ? 1 : 0;
      }
    }
    if (hits == 0) continue;

    // Apply: new ranges; points rebuilt inside the region, kept outside.
    std::vector<Point2> changed_endpoints;
    size_t k = 0;
    for (Scan& s : map.scans) {
      for (size_t i = 0; i < s.ranges.size(); ++i, ++k) {
        s.ranges[i] = new_ranges[k];
        if (!hit[k]) continue;
        const double ang = s.pose.theta + s.first_angle + static_cast<double>(i) * s.angle_step;
        changed_endpoints.push_back({s.pose.x + new_ranges[k] * std::cos(ang), s.pose.y + new_ranges[k] * std::sin(ang)});
      }
    }
    CellSet changed_cells;
    changed_cells.Reset(changed_endpoints.size());
    for (const Point2& p : changed_endpoints) changed_cells.Insert(CellKeyOf(p.x, p.y, opt.dedup_cell_m));
    const std::vector<Point2> rebuilt = PointsFromScans(map.scans, opt.dedup_cell_m);
    std::vector<Point2> points;
    points.reserve(map.points.size() + changed_cells.size());
    for (const Point2& p : map.points)
      if (!region.Contains(p)) points.push_back(p);
    SimulatedChange change;
    for (const Point2& p : rebuilt) {
      if (!region.Contains(p)) continue;
      points.push_back(p);
      if (changed_cells.Contains(CellKeyOf(p.x, p.y, opt.dedup_cell_m))) change.changed_points.push_back(p);
    }
    map.points = std::move(points);
    change.region_corners = {{region.x0, region.y0}, {region.x1, region.y0}, {region.x1, region.y1}, {region.x0, region.y1}};
    change.object_walls = std::move(objects);
    return change;
  }
  return Status::NotFound("map '" + map.id + "': no place for a visible change after " +
                          std::to_string(opt.max_attempts) + " attempts");
}

}  // namespace lmd
