// Nav2 map_server maps: a YAML file (image, resolution, origin, negate,
// occupied_thresh, free_thresh, mode) and a PGM image, read and written as
// nav2_map_server's map_io does. Only PGM images (P5 binary, P2 text) are
// read: map_saver's default, and what lmd writes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"

namespace lmd {

// nav_msgs/OccupancyGrid: cell (ix, iy) covers [ix, ix + 1) x [iy, iy + 1)
// cells of `resolution` m from `origin` (the pose of cell (0, 0)'s outer
// corner in the map frame); row iy = 0 is the bottom row (the image's last).
struct OccupancyMap {
  static constexpr int8_t kUnknown = -1;
  static constexpr int8_t kFree = 0;
  static constexpr int8_t kOccupied = 100;
  double resolution = 0.05;  // m per cell
  Pose2 origin;              // m, rad
  int width = 0, height = 0;
  std::vector<int8_t> cells;  // iy * width + ix: -1 unknown, 0..100 occupancy
  int8_t at(int ix, int iy) const { return cells[static_cast<size_t>(iy) * width + ix]; }
  // Map-frame centre of a cell.
  Point2 CellCentre(int ix, int iy) const;
};

// Reads `yaml_path` and the image it names (relative to the YAML's folder).
// Cells as map_server loads them: occ = (negate ? shade : 1 - shade), shade =
// pixel / maxval; trinary: occ > occupied_thresh -> 100, occ < free_thresh -> 0,
// else -1; scale: in between -> (occ - free) / (occupied - free) * 100; raw:
// the pixel value (0..100, else -1). InvalidArgument "<file>: ..." for a
// missing key, a bad value, an image that is no PGM or is cut short.
Result<OccupancyMap> ReadNav2Map(const std::string& yaml_path);

// Writes `yaml_path` and, beside it, the image (the YAML's name with .pgm):
// trinary mode, P5 pixels 0 (occupied, >= 65), 254 (free, <= 19.6) and 205
// (unknown), free_thresh 0.196 and occupied_thresh 0.65 so that map_server
// loads 205 as unknown (with map_saver's 0.25 it would load it as free).
Status WriteNav2Map(const std::string& yaml_path, const OccupancyMap& map);

}  // namespace lmd
