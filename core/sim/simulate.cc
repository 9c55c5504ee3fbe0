#include "core/sim/simulate.h"

#include <utility>

#include "core/sim/sim_random.h"

namespace lmd {
namespace {

// The laser log of building `index` of a simulation, in world coordinates.
LaserLog BuildingLog(const SimulationOptions& options, uint64_t index, const World& world) {
  RouteOptions route = options.route;
  route.building = 0;
  route.seed = MixSeed(options.route.seed, index);
  const std::vector<Pose2> poses = PlanRoute(world, route);
  return SimulateLog(world, poses, options.laser, MixSeed(options.world.seed ^ 0x5ca1ab1eULL, index));
}

}  // namespace

SimulationOptions DefaultDemoOptions() {
  SimulationOptions o;
  o.world.seed = 1;
  o.world.buildings = 1;
  o.route.seed = 1;
  o.route.length_m = 300.0;
  o.local_map.id_prefix = "sim";
  return o;
}

World DefaultDemoWorld() { return GenerateBuilding(DefaultDemoOptions().world, 0); }

LaserLog DefaultDemoLog() {
  const SimulationOptions o = DefaultDemoOptions();
  return BuildingLog(o, 0, DefaultDemoWorld());
}

size_t SimulateLocalMapsStreaming(const SimulationOptions& options, const LocalMapSink& sink) {
  const std::string prefix = options.local_map.id_prefix.empty() ? "sim" : options.local_map.id_prefix;
  LocalMapOptions lm = options.local_map;
  lm.id_prefix.clear();
  size_t delivered = 0;
  double travel_offset = 0.0;
  for (uint64_t b = 0;; ++b) {
    if (options.num_maps == 0 && b >= static_cast<uint64_t>(options.world.buildings)) break;
    if (options.num_maps > 0 && delivered >= options.num_maps) break;
    const World world = GenerateBuilding(options.world, b);
    const LaserLog log = BuildingLog(options, b, world);
    std::vector<LocalMap> maps = BuildLocalMaps(log, lm);
    if (maps.empty() && options.num_maps > 0 && b > 16 && delivered == 0) break;  // route too short: give up
    for (LocalMap& m : maps) {
      if (options.num_maps > 0 && delivered >= options.num_maps) break;
      m.id = prefix + "-" + std::to_string(delivered);
      m.truth.travel_start += travel_offset;
      m.truth.travel_end += travel_offset;
      ++delivered;
      if (!sink(std::move(m))) return delivered;
    }
    const std::vector<double> travel = CumulativeTravel(log);
    travel_offset += (travel.empty() ? 0.0 : travel.back()) + options.travel_gap_between_buildings_m;
  }
  return delivered;
}

std::vector<LocalMap> SimulateLocalMaps(const SimulationOptions& options) {
  std::vector<LocalMap> maps;
  SimulateLocalMapsStreaming(options, [&maps](LocalMap&& m) {
    maps.push_back(std::move(m));
    return true;
  });
  return maps;
}

}  // namespace lmd
