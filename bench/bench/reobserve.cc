#include "bench/bench/reobserve.h"

#include <cmath>
#include <random>

#include "core/localmap/pose_ops.h"

namespace lmd::bench {

LocalMap Reobserve(const LocalMap& map, uint64_t seed, double noise_m, double drop) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), shift(-5.0, 5.0), u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Pose2 motion{shift(rng), shift(rng), angle(rng)};  // old own frame in the new one
  LocalMap out;
  out.id = map.id + "-query";
  out.truth = map.truth;
  out.truth.global_frame = Compose(map.truth.global_frame, Inverse(motion));
  for (const Point2& p : map.points) {
    if (u(rng) < drop) continue;
    const Point2 q = TransformPoint(motion, p);
    out.points.push_back({q.x + noise(rng), q.y + noise(rng)});
  }
  for (const Pose2& p : map.trajectory) out.trajectory.push_back(Compose(motion, p));
  for (const Scan& scan : map.scans) {
    Scan moved = scan;
    moved.pose = Compose(motion, scan.pose);
    for (float& r : moved.ranges)
      if (r < moved.max_range) r = static_cast<float>(r + noise(rng));
    out.scans.push_back(std::move(moved));
  }
  return out;
}

}  // namespace lmd::bench
