#include "bench/eval/sequence_context.h"

#include <algorithm>
#include <cmath>

#include "core/localmap/pose_ops.h"

namespace lmd::eval {

std::vector<EarlierMap> EarlierMaps(const Dataset& d, const EvalQuery& q, const SequenceShape& shape,
                                    std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Pose2 truth = d.maps[q.map].truth.global_frame;
  std::vector<EarlierMap> out;
  for (size_t k = 1; k < shape.maps; ++k) {
    if (q.map < k * shape.spacing) break;
    const size_t index = q.map - k * shape.spacing;
    const LocalMap& earlier = d.maps[index];
    if (earlier.points.empty()) break;
    Pose2 odometry = Compose(Inverse(truth), earlier.truth.global_frame);
    const double travel = d.maps[q.map].truth.travel_start - earlier.truth.travel_start;
    const double direction = 2 * M_PI * u(*rng);
    odometry.x += 0.02 * travel * std::cos(direction);
    odometry.y += 0.02 * travel * std::sin(direction);
    odometry.theta += (2.0 * u(*rng) - 1.0) * travel * M_PI / 180.0;
    out.push_back({index, odometry, travel});
  }
  return out;
}

EvalQuery WithoutSequenceNeighbours(const Dataset& d, EvalQuery q, const SequenceShape& shape) {
  const size_t back = std::min(q.map / shape.spacing, shape.maps - 1) * shape.spacing;
  const double from = d.maps[q.map - back].truth.travel_start - kExcludedTravelM;
  const double to = d.maps[q.map].truth.travel_start + kExcludedTravelM;
  auto near_route = [&](size_t j) {
    const double t = d.maps[j].truth.travel_start;
    return t >= from && t <= to;
  };
  q.candidates.erase(std::remove_if(q.candidates.begin(), q.candidates.end(), near_route), q.candidates.end());
  q.places.erase(std::remove_if(q.places.begin(), q.places.end(), near_route), q.places.end());
  return q;
}

}  // namespace lmd::eval
