// Local map descriptors of simulated buildings for lmd-bench: the simulator
// (core/sim) streams local maps, the viewpoint planner and the describer turn
// them into Lmds, on several threads, in map order.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/describe/describer.h"
#include "core/types.h"

namespace lmd::bench {

struct SimDescriptorOptions {
  size_t maps = 1000;     // local maps to describe
  size_t queries = 50;    // query maps: stored maps seen again (see below)
  uint64_t seed = 1;      // world seed
  int threads = 2;        // describer threads
  double query_noise_m = 0.02;   // m, point noise of a query
  double query_drop = 0.1;       // fraction of a query's points dropped
  DescriberOptions describer;    // descriptor of maps and queries
};

struct SimDescriptors {
  std::vector<Lmd> maps;                // map n has id n
  std::vector<Lmd> queries;
  std::vector<uint64_t> query_sources;  // the stored map each query re-observes
  double simulate_s = 0;                // wall time in the simulator (world, route, laser, maps)
  double describe_s = 0;                // wall time planning + describing (all threads)
};

// Queries: the maps at evenly spaced indices, observed again: their own frame
// moved by a random rigid motion (so nothing may depend on it), Gaussian
// point noise, some points dropped, then planned and described afresh.
// `progress(done, total)` is called from the calling thread.
SimDescriptors SimulateDescriptors(const SimDescriptorOptions& options,
                                   const std::function<void(size_t, size_t)>& progress);

}  // namespace lmd::bench
