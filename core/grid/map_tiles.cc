#include "core/grid/map_tiles.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/grid/occupancy_grid.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"

namespace lmd {
namespace {

// Cell of a map-frame point (may lie outside: check bounds).
void CellOfPoint(const OccupancyMap& g, const Point2& p, int* ix, int* iy) {
  const double dx = p.x - g.origin.x, dy = p.y - g.origin.y;
  const double c = std::cos(g.origin.theta), s = std::sin(g.origin.theta);
  *ix = static_cast<int>(std::floor((c * dx + s * dy) / g.resolution));
  *iy = static_cast<int>(std::floor((-s * dx + c * dy) / g.resolution));
}

bool Inside(const OccupancyMap& g, int ix, int iy) { return ix >= 0 && iy >= 0 && ix < g.width && iy < g.height; }

// Range (m) from `o` along map-frame angle `a` to the first occupied or
// unknown cell; max_range when free all the way.
float CastInMap(const OccupancyMap& g, const Point2& o, double a, double max_range) {
  const double step = g.resolution * 0.5;
  const double ca = std::cos(a), sa = std::sin(a);
  for (double r = step; r < max_range; r += step) {
    int ix, iy;
    CellOfPoint(g, {o.x + r * ca, o.y + r * sa}, &ix, &iy);
    if (!Inside(g, ix, iy) || g.at(ix, iy) != OccupancyMap::kFree) return static_cast<float>(r);
  }
  return static_cast<float>(max_range);
}

}  // namespace

std::vector<MapTile> TilesFromOccupancyMap(const OccupancyMap& grid, const MapTileOptions& options) {
  std::vector<MapTile> tiles;
  if (grid.width <= 0 || grid.height <= 0 || !(options.stride_m > 0) || !(options.tile_m > 0)) return tiles;
  const double w = grid.width * grid.resolution, h = grid.height * grid.resolution;
  const int columns = std::max(1, static_cast<int>(std::ceil((w - options.tile_m) / options.stride_m)) + 1);
  const int rows = std::max(1, static_cast<int>(std::ceil((h - options.tile_m) / options.stride_m)) + 1);
  const double half = options.tile_m / 2;
  const int beams = std::max(1, static_cast<int>(std::lround(360.0 / options.beam_step_deg)));
  const double c = std::cos(grid.origin.theta), s = std::sin(grid.origin.theta);
  for (int row = 0; row < rows; ++row) {
    for (int col = 0; col < columns; ++col) {
      // Tile centre in the grid's own axes, then in the map frame.
      const double gx = std::min(half + col * options.stride_m, std::max(half, w - half));
      const double gy = std::min(half + row * options.stride_m, std::max(half, h - half));
      MapTile tile;
      tile.frame = {grid.origin.x + c * gx - s * gy, grid.origin.y + s * gx + c * gy, grid.origin.theta};
      const Pose2 to_tile = Inverse(tile.frame);
      const int x0 = std::max(0, static_cast<int>(std::floor((gx - half) / grid.resolution)));
      const int x1 = std::min(grid.width, static_cast<int>(std::ceil((gx + half) / grid.resolution)));
      const int y0 = std::max(0, static_cast<int>(std::floor((gy - half) / grid.resolution)));
      const int y1 = std::min(grid.height, static_cast<int>(std::ceil((gy + half) / grid.resolution)));
      std::vector<Point2> points;
      for (int iy = y0; iy < y1; ++iy) {
        for (int ix = x0; ix < x1; ++ix) {
          if (grid.at(ix, iy) >= 65) points.push_back(TransformPoint(to_tile, grid.CellCentre(ix, iy)));
        }
      }
      tile.map.points = DeduplicatePoints(points, options.point_cell_m);
      if (tile.map.points.size() < options.min_points) continue;
      // Virtual scans from free cells on a lattice.
      const int every = std::max(1, static_cast<int>(std::lround(options.scan_spacing_m / grid.resolution)));
      for (int iy = y0 + every / 2; iy < y1; iy += every) {
        for (int ix = x0 + every / 2; ix < x1; ix += every) {
          if (grid.at(ix, iy) != OccupancyMap::kFree) continue;
          const Point2 o = grid.CellCentre(ix, iy);
          Scan scan;
          const Point2 own = TransformPoint(to_tile, o);
          scan.pose = {own.x, own.y, 0.0};
          scan.first_angle = static_cast<float>(-M_PI);
          scan.angle_step = static_cast<float>(2 * M_PI / beams);
          scan.max_range = static_cast<float>(options.max_range_m);
          scan.ranges.resize(static_cast<size_t>(beams));
          for (int b = 0; b < beams; ++b) {
            const double a = tile.frame.theta + scan.first_angle + b * static_cast<double>(scan.angle_step);
            scan.ranges[static_cast<size_t>(b)] = CastInMap(grid, o, a, options.max_range_m);
          }
          tile.map.trajectory.push_back(scan.pose);
          tile.map.scans.push_back(std::move(scan));
        }
      }
      tile.map.id = options.id_prefix + "-" + std::to_string(col) + "-" + std::to_string(row);
      tiles.push_back(std::move(tile));
    }
  }
  return tiles;
}

OccupancyMap RasterizeLocalMaps(const std::vector<LocalMap>& maps, const std::vector<Pose2>& frames,
                                double resolution) {
  OccupancyMap out;
  out.resolution = resolution;
  // Each map's own grid (free space and points) at the output resolution.
  GridOptions options;
  options.cell_m = resolution;
  std::vector<OccupancyGrid> grids;
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  for (size_t m = 0; m < maps.size() && m < frames.size(); ++m) {
    grids.push_back(BuildOccupancyGrid(maps[m], 0.0, options));
    const OccupancyGrid& g = grids.back();
    for (int corner = 0; corner < 4; ++corner) {
      const Point2 own{g.min_x() + (corner & 1 ? g.width() : 0) * resolution,
                       g.min_y() + (corner & 2 ? g.height() : 0) * resolution};
      const Point2 p = TransformPoint(frames[m], own);
      lo_x = std::min(lo_x, p.x), hi_x = std::max(hi_x, p.x), lo_y = std::min(lo_y, p.y), hi_y = std::max(hi_y, p.y);
    }
  }
  if (grids.empty()) return out;
  out.origin = {std::floor(lo_x / resolution) * resolution, std::floor(lo_y / resolution) * resolution, 0.0};
  out.width = static_cast<int>(std::ceil((hi_x - out.origin.x) / resolution)) + 1;
  out.height = static_cast<int>(std::ceil((hi_y - out.origin.y) / resolution)) + 1;
  out.cells.assign(static_cast<size_t>(out.width) * out.height, OccupancyMap::kUnknown);
  for (size_t m = 0; m < grids.size(); ++m) {
    const OccupancyGrid& g = grids[m];
    // Free: each output cell takes the state of the map cell under its
    // centre (sampling the output side keeps rotated maps free of holes).
    const Pose2 to_own = Inverse(frames[m]);
    int ax = out.width, ay = out.height, bx = -1, by = -1;
    for (int corner = 0; corner < 4; ++corner) {
      const Point2 own{g.min_x() + (corner & 1 ? g.width() : 0) * resolution,
                       g.min_y() + (corner & 2 ? g.height() : 0) * resolution};
      int ix, iy;
      CellOfPoint(out, TransformPoint(frames[m], own), &ix, &iy);
      ax = std::min(ax, ix), ay = std::min(ay, iy), bx = std::max(bx, ix), by = std::max(by, iy);
    }
    for (int iy = std::max(0, ay); iy <= std::min(out.height - 1, by); ++iy) {
      for (int ix = std::max(0, ax); ix <= std::min(out.width - 1, bx); ++ix) {
        int gx, gy;
        g.CellOf(TransformPoint(to_own, out.CellCentre(ix, iy)), &gx, &gy);
        const CellState state = g.at(gx, gy);
        int8_t& cell = out.cells[static_cast<size_t>(iy) * out.width + ix];
        if (state == CellState::kFree && cell == OccupancyMap::kUnknown) cell = OccupancyMap::kFree;
      }
    }
  }
  for (size_t m = 0; m < grids.size(); ++m) {  // points straight into their cells: no wall lost to sampling
    for (const Point2& p : maps[m].points) {
      int ix, iy;
      CellOfPoint(out, TransformPoint(frames[m], p), &ix, &iy);
      if (Inside(out, ix, iy)) out.cells[static_cast<size_t>(iy) * out.width + ix] = OccupancyMap::kOccupied;
    }
  }
  return out;
}

}  // namespace lmd
