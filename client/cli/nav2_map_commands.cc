// import-map and export-map of lmdctl: Nav2 map_server maps (YAML + PGM) in
// and out of a collection (core/io/nav2_map.h, core/grid/map_tiles.h).
#include <cstdio>
#include <cstdlib>

#include "client/cli/anchored_maps.h"
#include "client/cli/commands.h"
#include "client/cli/insert_maps.h"
#include "core/grid/map_tiles.h"
#include "core/io/nav2_map.h"
#include "proto/convert.h"

namespace lmd::cli {
namespace {

std::string Stem(const std::string& path) {
  std::string name = path.substr(path.find_last_of('/') + 1);
  const size_t dot = name.rfind('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

}  // namespace

int ImportMapCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  const std::string yaml = collection.empty() ? "" : Required(ctx.args, "yaml");
  if (collection.empty() || yaml.empty()) return 2;
  MapTileOptions options;
  Result<double> tile = GetMetres(ctx.args, "tile", options.tile_m, 2.0, 100.0);
  if (!tile.ok()) return Fail(tile.status().message(), 2);
  Result<double> stride = GetMetres(ctx.args, "stride", *tile / 2, 0.5, 100.0);
  if (!stride.ok()) return Fail(stride.status().message(), 2);
  options.tile_m = *tile;
  options.stride_m = *stride;
  options.id_prefix = Stem(yaml);
  Result<OccupancyMap> grid = ReadNav2Map(yaml);
  if (!grid.ok()) return Fail(grid.status().message() + " (no map stored)");
  const std::vector<MapTile> tiles = TilesFromOccupancyMap(*grid, options);
  if (tiles.empty()) return Fail(yaml + ": no occupied cells to make a local map of (no map stored)");
  std::vector<LocalMap> maps;
  std::vector<Pose2> frames;
  for (const MapTile& t : tiles) maps.push_back(t.map), frames.push_back(t.frame);
  if (int code = InsertLocalMaps(ctx, collection, maps, frames, "import " + yaml, "", nullptr)) return code;
  if (!ctx.json) {
    std::printf("imported %zu tiles (%g m every %g m) of %s (%d x %d cells at %g m) into '%s', anchored in its frame\n",
                maps.size(), options.tile_m, options.stride_m, yaml.c_str(), grid->width, grid->height,
                grid->resolution, collection.c_str());
  }
  return 0;
}

int ExportMapCommand(const CommandContext& ctx) {
  const std::string collection = Required(ctx.args, "collection");
  const std::string out = collection.empty() ? "" : Required(ctx.args, "out");
  if (collection.empty() || out.empty()) return 2;
  Result<double> resolution = GetMetres(ctx.args, "resolution", 0.05, 0.01, 1.0);
  if (!resolution.ok()) return Fail(resolution.status().message(), 2);
  AnchoredMaps site;
  if (ctx.args.Has("id")) {
    v1::GetMapRequest get;
    get.set_collection(collection);
    get.set_map_id(ctx.args.Get("id"));
    v1::GetMapResponse response;
    const grpc::Status status = ctx.client.GetMap(get, &response);
    if (!status.ok()) return FailCall(status);
    site.maps.push_back(FromProto(response.map().map()));
    site.anchors.push_back(Pose2{});  // the map's own frame
  } else {
    const grpc::Status read = ReadAnchoredMaps(ctx.client, collection, /*with_derived=*/false, &site);
    if (!read.ok()) return FailCall(read);
    if (site.maps.empty()) {
      return Fail("collection '" + collection + "' has no anchored maps (maps stored with a pose hint, as " +
                  "import-map stores them): give --id ID to export one map in its own frame");
    }
  }
  const OccupancyMap grid = RasterizeLocalMaps(site.maps, site.anchors, *resolution);
  const Status written = WriteNav2Map(out, grid);
  if (!written.ok()) return Fail(written.message());
  if (ctx.json) {
    std::printf("{\"yaml\":\"%s\",\"width\":%d,\"height\":%d,\"resolution\":%g,\"maps\":%zu}\n", out.c_str(), grid.width,
                grid.height, grid.resolution, site.maps.size());
  } else {
    std::printf("wrote %s (%d x %d cells at %g m, origin (%.2f, %.2f) m) from %zu %s\n", out.c_str(), grid.width,
                grid.height, grid.resolution, grid.origin.x, grid.origin.y, site.maps.size(),
                ctx.args.Has("id") ? "map in its own frame" : "anchored maps");
  }
  return 0;
}

}  // namespace lmd::cli
