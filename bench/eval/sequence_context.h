// A sequence query as lmd-eval asks it (--mode sequence, sequence-misses):
// the robot's earlier maps, the odometry to them with its drift, and the
// stored maps a fair query leaves out around them.
#pragma once

#include <cstddef>
#include <random>
#include <vector>

#include "bench/eval/eval_dataset.h"
#include "core/types.h"

namespace lmd::eval {

// How a sequence is drawn: this many maps in all, each `spacing` maps (about
// 1 m each) before the next; odometry to them off by 2 % of the distance and
// up to 1 deg per metre.
struct SequenceShape {
  size_t maps = 3;
  size_t spacing = 5;
};

struct EarlierMap {
  size_t map = 0;     // index in the dataset
  Pose2 in_newest;    // its own frame in the query's, as the drifting odometry says
  double travel_m = 0.0;
};

// Query `q`'s earlier maps, newest first (fewer at the start of a log, none
// past an empty map), their odometry drawn from `rng`.
std::vector<EarlierMap> EarlierMaps(const Dataset& d, const EvalQuery& q, const SequenceShape& shape,
                                    std::mt19937_64* rng);

// `q` with the stored maps within kExcludedTravelM of travel of any map of
// its sequence left out, as candidates and as places: else an earlier map
// finds its own route neighbours, which place the newest map where its own
// excluded neighbours lie.
EvalQuery WithoutSequenceNeighbours(const Dataset& d, EvalQuery q, const SequenceShape& shape);

}  // namespace lmd::eval
