// Picture of one local map, like the paper's Fig. 1b / Fig. 4: occupancy
// grid (free light, occupied dark), wall primitives, room cells and the cells
// kept by the 90 % rule, trajectory, the CoG and CoR viewpoints (both marked,
// the chosen one larger) and the descriptor's features.
#pragma once

#include <string>

#include "core/types.h"
#include "core/viewpoint/viewpoint.h"

namespace lmd {

struct LocalMapSvgOptions {
  double width_px = 900.0;
  bool grid = true;        // occupancy grid cells
  bool walls = true;       // wall primitives
  bool rooms = true;       // room cells and the 90 % peak cells
  bool features = true;    // features of `lmd` (if given)
  std::string title;       // drawn at the top; empty = map id
};

// SVG document (own frame of the map, metres). `lmd` may be null.
std::string RenderLocalMapSvg(const LocalMap& map, const ViewpointPlan& plan, const Lmd* lmd,
                              const LocalMapSvgOptions& options = {});

}  // namespace lmd
