#include "bench/bench/sim_descriptors.h"

#include <chrono>
#include <cmath>
#include <random>
#include <thread>

#include "bench/bench/reobserve.h"
#include "core/describe/describer.h"
#include "core/sim/simulate.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd::bench {
namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Describes maps[i] into out[i] on `threads` threads.
void DescribeBatch(const std::vector<LocalMap>& maps, const DescriberOptions& describer, std::vector<Lmd>* out,
                   int threads) {
  out->resize(maps.size());
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      for (size_t i = static_cast<size_t>(t); i < maps.size(); i += static_cast<size_t>(threads))
        (*out)[i] = Describe(maps[i], PlanViewpoint(maps[i]), describer);
    });
  }
  for (auto& w : workers) w.join();
}

}  // namespace

SimDescriptors SimulateDescriptors(const SimDescriptorOptions& options,
                                   const std::function<void(size_t, size_t)>& progress) {
  SimDescriptors result;
  SimulationOptions sim;
  sim.world.seed = options.seed;
  sim.route.seed = options.seed;
  sim.num_maps = options.maps;
  sim.local_map.id_prefix = "sim";
  // Query sources: evenly spaced map indices.
  std::vector<size_t> sources;
  for (size_t q = 0; q < options.queries && options.maps > 0; ++q)
    sources.push_back(std::min(options.maps - 1, (2 * q + 1) * options.maps / (2 * options.queries)));
  std::vector<LocalMap> query_maps;
  size_t next_source = 0;
  const int threads = std::max(1, options.threads);
  const size_t batch_size = 256;
  std::vector<LocalMap> batch;
  std::vector<Lmd> described;
  auto flush = [&] {
    const auto start = std::chrono::steady_clock::now();
    DescribeBatch(batch, options.describer, &described, threads);
    result.describe_s += Seconds(start);
    for (Lmd& lmd : described) result.maps.push_back(std::move(lmd));
    batch.clear();
    if (progress) progress(result.maps.size(), options.maps);
  };
  auto sim_start = std::chrono::steady_clock::now();
  double in_sink_s = 0;
  SimulateLocalMapsStreaming(sim, [&](LocalMap&& map) {
    const auto start = std::chrono::steady_clock::now();
    const size_t n = result.maps.size() + batch.size();
    if (n >= options.maps) return false;
    while (next_source < sources.size() && sources[next_source] == n) {
      query_maps.push_back(Reobserve(map, options.seed * 1000003 + n, options.query_noise_m, options.query_drop));
      result.query_sources.push_back(n);
      ++next_source;
    }
    map.id.clear();
    batch.push_back(std::move(map));
    if (batch.size() == batch_size) flush();
    in_sink_s += Seconds(start);
    return result.maps.size() + batch.size() < options.maps;
  });
  if (!batch.empty()) flush();
  result.simulate_s = Seconds(sim_start) - in_sink_s;
  const auto start = std::chrono::steady_clock::now();
  DescribeBatch(query_maps, options.describer, &result.queries, threads);
  result.describe_s += Seconds(start);
  return result;
}

}  // namespace lmd::bench
