// Simulated 2D worlds: Manhattan-like buildings of wall segments (rooms off a
// lattice of corridors, doors, clutter, a few oblique walls) and a ray caster
// that walks a uniform grid of cells (never loops over all segments).
#pragma once

#include <cstdint>
#include <vector>

#include "core/types.h"

namespace lmd {

// A wall: the segment from a to b (m).
struct Segment {
  Point2 a;
  Point2 b;
};

// A door: where a route may leave a corridor to visit a room.
struct Door {
  Point2 corridor_point;  // on the corridor centreline, in front of the door
  Point2 door_centre;     // middle of the opening in the wall
  Point2 room_centre;     // free point inside the room; the polyline
                          //   corridor_point -> door_centre -> room_centre is clear
};

// The free-space skeleton of one building, used by the route planner.
// Corridor centrelines: vertical at x = corridor_x[i] for y in
// [corridor_y.front(), corridor_y.back()], horizontal alike; every crossing is
// an intersection. All coordinates in the world frame.
struct BuildingLayout {
  Point2 min_corner;               // outer wall bounding box
  Point2 max_corner;
  std::vector<double> corridor_x;  // sorted
  std::vector<double> corridor_y;  // sorted
  double corridor_width = 2.0;     // m
  std::vector<Door> doors;
};

// Walls plus a grid for ray casting. Immutable after construction.
class World {
 public:
  World() = default;
  // Builds the ray-casting grid over the walls' bounding box (cell_m cells).
  World(std::vector<Segment> walls, std::vector<BuildingLayout> buildings, double cell_m = 1.0);

  const std::vector<Segment>& walls() const { return walls_; }
  const std::vector<BuildingLayout>& buildings() const { return buildings_; }

  // Distance (m) from `origin` along direction `angle` (rad, world frame) to
  // the first wall, or max_range if none is closer than max_range.
  double CastRay(const Point2& origin, double angle, double max_range) const;

 private:
  std::vector<Segment> walls_;
  std::vector<BuildingLayout> buildings_;
  double cell_m_ = 1.0;
  double min_x_ = 0.0, min_y_ = 0.0;
  int nx_ = 0, ny_ = 0;
  std::vector<uint32_t> cell_start_;  // CSR: segments of cell c are
  std::vector<uint32_t> cell_walls_;  //   cell_walls_[cell_start_[c] .. cell_start_[c+1])
};

struct WorldOptions {
  uint64_t seed = 1;                // all geometry follows from it
  int buildings = 1;                // buildings, side by side on a tile grid
  double tile_m = 200.0;            // m between building origins (> building size)
  int min_corridors = 3;            // corridor lines per axis, inclusive range
  int max_corridors = 4;            //   (>= 2: the outer ring always exists)
  double min_block_m = 9.0;         // m between neighbouring corridor lines
  double max_block_m = 16.0;
  double corridor_width_m = 2.0;    // m
  double min_room_m = 3.0;          // m, room width along its block side
  double max_room_m = 6.0;
  double door_width_m = 1.0;        // m
  double clutter_per_room = 1.5;    // mean clutter boxes per room (0.3..1 m)
  double oblique_fraction = 0.15;   // fraction of rooms with an oblique wall
  double corridor_clutter_probability = 0.3;  // chance a corridor stretch has a box by a wall
  double hall_probability = 0.15;   // chance a block is one hall with pillars, not rooms
};

// A world with options.buildings buildings; building k is
// GenerateBuilding(options, k). Deterministic for a given options.seed.
World GenerateWorld(const WorldOptions& options);

// Building `index` alone (its own World), placed at tile (index % 64,
// index / 64) * tile_m. Its geometry depends only on (seed, index), so huge
// worlds can be generated one building at a time.
World GenerateBuilding(const WorldOptions& options, uint64_t index);

}  // namespace lmd
