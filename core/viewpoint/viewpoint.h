// Viewpoint planner (paper sec. "Approach"): places a frame in a local map
// from the map's structure alone, so that two maps of the same place get
// (nearly) the same frame whatever their own frames and routes were.
//   heading = dominant orientation (entropy compass, orientation.h);
//   origin  = CoG (centre of gravity of the wall-primitive cells) or
//             CoR (centre of the "room" cells: free-cell rectangles sampled
//             densely, histograms f_x, f_y of their cells, cells where both
//             exceed room_peak_fraction of their peak, centre of gravity).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/grid/occupancy_grid.h"
#include "core/types.h"
#include "core/viewpoint/orientation.h"
#include "core/viewpoint/walls.h"

namespace lmd {

enum class Planner { kCoG, kCoR };

// Name of a planner: "cog" / "cor".
const char* PlannerName(Planner planner);

struct ViewpointOptions {
  // Default = the planner with the smaller median viewpoint distance over the
  // relevant pairs of the nine real logs (`lmd-eval viewpoints`): CoG, median
  // of the per-log medians 2.1 m vs 3.1 m for CoR (CoR has more pairs within
  // 0.5 m on 6 of 9 logs but a heavier tail: its 90 % peak jumps between rooms).
  Planner planner = Planner::kCoG;
  OrientationOptions orientation;  // entropy compass
  GridOptions grid;                // cell_m = 0.1 (paper)
  WallOptions walls;
  // CoR: one seed every room_seed_stride cells along each grid axis (free
  // cells only); each grows the largest free axis-aligned rectangle it can.
  int room_seed_stride = 2;
  double room_min_area_m2 = 0.5;      // m^2; smaller rectangles are dropped
  double room_peak_fraction = 0.9;    // keep cells with f_x, f_y > this * peak (paper: 0.9)
};

// Everything the planner computed, for pictures and debugging.
struct ViewpointPlan {
  Frame frame;                        // the chosen planner's frame
  Frame cog;                          // CoG frame (same heading)
  Frame cor;                          // CoR frame (same heading)
  OccupancyGrid grid;                 // rotated by frame.heading
  std::vector<WallPrimitive> walls;   // in grid cells
  std::vector<uint8_t> room_cells;    // per grid cell: 1 = inside a room rectangle
  std::vector<uint8_t> room_peak;     // per grid cell: 1 = kept by the 90 % rule
};

// Plans both viewpoints. Fallbacks: no wall cells -> CoG = centroid of the
// points; no room cells -> CoR = CoG; empty map -> origin (0, 0), heading 0.
ViewpointPlan PlanViewpointDetailed(const LocalMap& map, const ViewpointOptions& options = {});

// PlanViewpointDetailed(map, options).frame (without the room search when
// the planner is CoG). `known_heading`: the map's compass heading with
// options.orientation, where the caller has it already.
Frame PlanViewpoint(const LocalMap& map, const ViewpointOptions& options = {},
                    std::optional<double> known_heading = std::nullopt);

// Own-frame point -> coordinates in `frame` (R(-heading) (p - origin)), and back.
Point2 ToFrame(const Frame& frame, const Point2& own);
Point2 FromFrame(const Frame& frame, const Point2& in_frame);

}  // namespace lmd
