// One-call simulation: worlds -> routes -> laser logs -> local maps. The demo
// world (small, a few hundred local maps with loops) and streaming generation
// of very many local maps for scale benchmarks (one building at a time).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/io/laser_log.h"
#include "core/localmap/local_map_builder.h"
#include "core/sim/laser.h"
#include "core/sim/route.h"
#include "core/sim/world.h"
#include "core/types.h"

namespace lmd {

struct SimulationOptions {
  WorldOptions world;          // world.seed drives everything
  RouteOptions route;          // route.length_m = travel per building
  LaserOptions laser;
  LocalMapOptions local_map;   // id_prefix defaults to "sim" below
  // Total local maps wanted; buildings are added (each with a route of
  // route.length_m) until it is reached. 0 = world.buildings buildings.
  size_t num_maps = 0;
  // m of travel added between buildings so that maps of different buildings
  // are never within min_travel_gap of each other by accident.
  double travel_gap_between_buildings_m = 100.0;
};

// The demo: one building (seed 1), a 300 m route with loops, 1 deg laser;
// about 300 local maps.
SimulationOptions DefaultDemoOptions();
World DefaultDemoWorld();
LaserLog DefaultDemoLog();  // the demo route's laser log (world frame)

// Called once per local map, in route order; return false to stop early.
using LocalMapSink = std::function<bool(LocalMap&&)>;

// Streams the local maps of options: building by building, each building
// generated, driven and discarded in turn (memory stays per building). Map
// ids are "<id_prefix>-<n>" with n counting over all buildings. Returns the
// number of maps delivered.
size_t SimulateLocalMapsStreaming(const SimulationOptions& options, const LocalMapSink& sink);

// All local maps of options in one vector (use the streaming form for 10^5+
// maps with scans: ~15 KB each).
std::vector<LocalMap> SimulateLocalMaps(const SimulationOptions& options);

}  // namespace lmd
