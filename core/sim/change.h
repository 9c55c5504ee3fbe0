// The change simulator of the evaluation protocol (DESIGN.md §4): puts new
// objects into a local map as the robot's laser would have seen them.
#pragma once

#include <random>
#include <vector>

#include "core/sim/world.h"
#include "core/status.h"
#include "core/types.h"

namespace lmd {

struct ChangeOptions {
  double min_side_m = 1.0;        // m, region sides w, h uniform in [min, max]
  double max_side_m = 2.0;        //   (paper: [1, 2] m)
  int min_objects = 2;            // small rectangles per region, inclusive
  int max_objects = 5;
  double min_object_m = 0.2;      // m, object side lengths
  double max_object_m = 0.6;
  double max_place_range_m = 8.0; // m, region centre at most this far along a beam
  double robot_clearance_m = 0.3; // m, no scan pose within this of the region
  int max_attempts = 200;         // region draws before giving up
  double dedup_cell_m = 0.1;      // m, point dedup grid (as the builder's)
};

// The change, in the map's own frame.
struct SimulatedChange {
  std::vector<Point2> region_corners;  // 4 corners, counter-clockwise (axis-aligned box)
  std::vector<Point2> changed_points;  // new points produced by the objects
  std::vector<Segment> object_walls;   // object outlines (for pictures)
};

// Draws an axis-aligned region centred at a free point the laser saw (along a
// beam, before its return), away from every scan pose; fills it with small
// axis-aligned rectangles; re-ray-casts every beam of map.scans against them
// (range = min(old, hit)); re-draws when no beam hits an object. map.points
// outside the region are kept as they are (a map integrates many views, so
// occlusion behind the objects is not applied); inside the region they are
// rebuilt from the new scans. Returns InvalidArgument if the map has no scans,
// NotFound if max_attempts draws all fail. Deterministic for a given rng state.
Result<SimulatedChange> ApplySimulatedChange(LocalMap& map, std::mt19937_64& rng,
                                             const ChangeOptions& options = {});

}  // namespace lmd
