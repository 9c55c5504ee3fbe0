// Between whole-site occupancy maps (Nav2's, io/nav2_map.h) and lmd's local
// maps. A saved map is cut into overlapping square tiles of local-map size,
// each a LocalMap in its own frame (the tile's centre, axes of the map) with
// the occupied cells as points and the free cells as free space the way the
// store reads it: virtual 360-degree scans from free cells, ray-cast in the
// map, so that a beam crosses free cells and ends at a wall or at unknown
// space (prepared_map.h builds free space from scans). The other way, maps
// placed in one frame (a collection's anchored maps) are rasterised into
// one occupancy map.
#pragma once

#include <string>
#include <vector>

#include "core/io/nav2_map.h"
#include "core/types.h"

namespace lmd {

struct MapTileOptions {
  // m; tile side and the step between tile centres. A 5 m local map of a
  // real log spans about 10-20 m; tiles overlap by half so that a robot's map
  // falls mostly inside one of them.
  double tile_m = 12.0;
  double stride_m = 6.0;
  size_t min_points = 20;     // tiles with fewer occupied points are not made
  double point_cell_m = 0.1;  // m; points kept one per cell (as local maps keep theirs)
  // Virtual scans: origins on a lattice of this spacing (m) at free cells,
  // beams every beam_step_deg over 360 deg, up to max_range_m.
  double scan_spacing_m = 2.0;
  double beam_step_deg = 1.0;
  double max_range_m = 8.0;
  std::string id_prefix = "map";  // tile ids "<prefix>-<column>-<row>"
};

struct MapTile {
  LocalMap map;      // own frame = the tile's centre
  Pose2 frame;       // the own frame's pose in the occupancy map's frame (a pose hint)
};

// Tiles of `grid` holding at least min_points occupied points, row by row.
std::vector<MapTile> TilesFromOccupancyMap(const OccupancyMap& grid, const MapTileOptions& options = {});

// One occupancy map (cells of `resolution` m, axes of the common frame)
// covering `maps`, each placed by its pose in `frames`: occupied where a
// point falls, free where its free space is (its scans, else its
// trajectory; occupancy_grid.h), unknown elsewhere; occupied wins.
OccupancyMap RasterizeLocalMaps(const std::vector<LocalMap>& maps, const std::vector<Pose2>& frames,
                                double resolution = 0.05);

}  // namespace lmd
