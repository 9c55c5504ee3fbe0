// Robot routes through a simulated building: a random walk on the corridor
// lattice (no immediate U-turns), so crossings and corridors are revisited
// from other directions, with detours into rooms through their doors.
#pragma once

#include <cstdint>
#include <vector>

#include "core/sim/world.h"
#include "core/types.h"

namespace lmd {

struct RouteOptions {
  uint64_t seed = 1;
  double length_m = 300.0;            // m of travel (turns in place add none)
  int building = 0;                   // index into World::buildings()
  double pose_spacing_m = 0.5;        // m between consecutive poses (= scans)
  double max_turn_rad = 0.35;         // rad: larger turns get in-place poses
  double lateral_jitter_m = 0.3;      // m, random offset from corridor centrelines
  double room_visit_probability = 0.25;  // per door passed
};

// Poses (world frame) along the route, the first at a random crossing; one
// pose every pose_spacing_m of travel and extra poses while turning so that
// consecutive headings differ by at most max_turn_rad. Empty if the building
// index is out of range.
std::vector<Pose2> PlanRoute(const World& world, const RouteOptions& options);

}  // namespace lmd
