#include "core/change/sightings.h"

#include <algorithm>
#include <cmath>

namespace lmd {
namespace {

// How far beam i of `scan` saw free space: its range, or the clearing
// distance when it had no return; negative when the range is not usable.
double Reach(const Scan& scan, size_t i, double no_return_clear_m) {
  const double r = scan.ranges[i];
  if (!(r >= 0.0) || !std::isfinite(r)) return -1.0;
  return r < scan.max_range ? r : std::min<double>(scan.max_range, no_return_clear_m);
}

}  // namespace

std::vector<Sightings> CountSightings(const std::vector<Point2>& points, const std::vector<Scan>& scans,
                                      const SightingOptions& options) {
  std::vector<Sightings> out(points.size());
  const double two_pi = 2.0 * M_PI;
  const size_t bound = std::max<size_t>(options.max_point_scan_pairs, 1);
  const size_t per_scan = std::max<size_t>(points.size(), 1);
  const size_t stride = (scans.size() * per_scan + bound - 1) / bound;  // ceil; 0 when there are no scans
  for (size_t s = 0; s < scans.size(); s += std::max<size_t>(stride, 1)) {
    const Scan& scan = scans[s];
    const size_t n = scan.ranges.size();
    const double step = scan.angle_step;
    if (n == 0 || !(std::fabs(step) > 0.0) || !std::isfinite(step) || !std::isfinite(scan.pose.x) ||
        !std::isfinite(scan.pose.y) || !std::isfinite(scan.pose.theta) || !std::isfinite(scan.first_angle)) {
      continue;
    }
    const double beams_per_turn = two_pi / std::fabs(step);
    for (size_t k = 0; k < points.size(); ++k) {
      const double dx = points[k].x - scan.pose.x, dy = points[k].y - scan.pose.y;
      const double d = std::hypot(dx, dy);
      if (!(d > options.margin_m) || !std::isfinite(d)) continue;  // at the sensor, or NaN
      // Beam index of the bearing, counted in the scan's direction, within one turn.
      double u = (std::atan2(dy, dx) - scan.pose.theta - scan.first_angle) / step;
      u = std::fmod(u, beams_per_turn);
      if (u < 0) u += beams_per_turn;
      size_t i = static_cast<size_t>(std::lround(u));
      if (static_cast<double>(i) >= beams_per_turn - 0.5) i = 0;  // rounded up to a full turn
      if (i >= n) continue;  // outside the field of view
      const double reach = Reach(scan, i, options.no_return_clear_m);
      if (reach < 0.0) continue;
      if (std::fabs(reach - d) <= options.margin_m && scan.ranges[i] < scan.max_range) {
        ++out[k].returns;
        continue;
      }
      bool through = reach > d + options.margin_m;
      for (size_t j : {i - 1, i + 1}) {  // i - 1 wraps to a huge index at i = 0: skipped
        if (j < n) through = through && Reach(scan, j, options.no_return_clear_m) > d + options.margin_m;
      }
      if (through) ++out[k].through;
    }
  }
  return out;
}

}  // namespace lmd
