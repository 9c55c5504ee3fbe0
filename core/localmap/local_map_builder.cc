#include "core/localmap/local_map_builder.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/cell_set.h"
#include "core/localmap/pose_ops.h"

namespace lmd {

std::vector<double> CumulativeTravel(const LaserLog& log) {
  std::vector<double> travel(log.scans.size(), 0.0);
  for (size_t i = 1; i < log.scans.size(); ++i) {
    const Pose2& a = log.scans[i - 1].pose;
    const Pose2& b = log.scans[i].pose;
    travel[i] = travel[i - 1] + std::hypot(b.x - a.x, b.y - a.y);
  }
  return travel;
}

std::vector<Point2> DeduplicatePoints(const std::vector<Point2>& points, double dedup_cell_m) {
  CellSet seen;
  seen.Reset(points.size());
  std::vector<Point2> kept;
  kept.reserve(points.size());
  for (const Point2& p : points) {
    if (seen.Insert(CellKeyOf(p.x, p.y, dedup_cell_m))) kept.push_back(p);
  }
  return kept;
}

std::vector<Point2> PointsFromScans(const std::vector<Scan>& scans, double dedup_cell_m) {
  size_t beams = 0;
  for (const Scan& s : scans) beams += s.ranges.size();
  CellSet seen;
  seen.Reset(std::min<size_t>(beams, 1 << 16));
  std::vector<Point2> points;
  points.reserve(beams / 4);
  std::vector<double> cb, sb;  // beam directions in the sensor frame, cached
  float cached_first = 0, cached_step = 0;
  size_t cached_n = 0;
  for (const Scan& scan : scans) {
    const size_t n = scan.ranges.size();
    if (n != cached_n || scan.first_angle != cached_first || scan.angle_step != cached_step) {
      cb.resize(n);
      sb.resize(n);
      for (size_t i = 0; i < n; ++i) {
        const double a = static_cast<double>(scan.first_angle) + static_cast<double>(i) * scan.angle_step;
        cb[i] = std::cos(a);
        sb[i] = std::sin(a);
      }
      cached_n = n;
      cached_first = scan.first_angle;
      cached_step = scan.angle_step;
    }
    const double c = std::cos(scan.pose.theta), s = std::sin(scan.pose.theta);
    for (size_t i = 0; i < n; ++i) {
      const float r = scan.ranges[i];
      if (!(r >= 0.0f) || r >= scan.max_range) continue;
      const double lx = r * cb[i], ly = r * sb[i];
      const Point2 p{scan.pose.x + c * lx - s * ly, scan.pose.y + s * lx + c * ly};
      if (seen.Insert(CellKeyOf(p.x, p.y, dedup_cell_m))) points.push_back(p);
    }
  }
  return points;
}

std::vector<LocalMap> BuildLocalMaps(const LaserLog& log, const LocalMapOptions& options) {
  std::vector<LocalMap> maps;
  if (log.scans.empty() || !(options.length_m > 0) || !(options.step_m > 0)) return maps;
  const std::vector<double> travel = CumulativeTravel(log);
  const double total = travel.back();
  const double eps = 1e-9;
  size_t previous_first = static_cast<size_t>(-1);
  std::vector<Scan> own;
  for (double k = 0;; ++k) {
    const double start = k * options.step_m;
    const double end = start + options.length_m;
    if (end > total + eps) break;
    const size_t first = static_cast<size_t>(
        std::lower_bound(travel.begin(), travel.end(), start - eps) - travel.begin());
    const size_t last_excl = static_cast<size_t>(
        std::upper_bound(travel.begin(), travel.end(), end + eps) - travel.begin());
    // Go past the starts that give this window again at once, so that a jump
    // in the log costs one step, not one per step_m: if the window is empty
    // (the next scan lies beyond its end), to the last start whose window is
    // still empty; else past every start up to travel[first].
    if (first < travel.size()) {
      const double next = first >= last_excl
                              ? std::ceil((travel[first] - eps - options.length_m) / options.step_m) - 1
                              : std::floor((travel[first] + eps) / options.step_m);
      k = std::max(k, next);
    }
    if (first >= last_excl || first == previous_first) continue;
    previous_first = first;

    const Pose2 origin = log.scans[first].pose;
    const Pose2 to_own = Inverse(origin);
    own.clear();
    own.reserve(last_excl - first);
    LocalMap map;
    map.trajectory.reserve(last_excl - first);
    for (size_t i = first; i < last_excl; ++i) {
      Scan s = log.scans[i];
      s.pose = i == first ? Pose2{0.0, 0.0, 0.0} : Compose(to_own, s.pose);
      map.trajectory.push_back(s.pose);
      own.push_back(std::move(s));
    }
    map.points = PointsFromScans(own, options.dedup_cell_m);
    const size_t index = maps.size();
    map.id = options.id_prefix.empty() ? std::to_string(index)
                                       : options.id_prefix + "-" + std::to_string(index);
    map.heading_drift_rad_per_m = options.heading_drift_rad_per_m;
    map.truth.global_frame = origin;
    map.truth.travel_start = travel[first];
    map.truth.travel_end = travel[last_excl - 1];
    if (options.keep_scans) map.scans = std::move(own);
    maps.push_back(std::move(map));
  }
  return maps;
}

}  // namespace lmd
