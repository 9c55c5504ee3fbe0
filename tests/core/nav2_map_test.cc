// Nav2 maps in and out: the YAML + PGM that WriteNav2Map writes loads in a
// reader that follows nav2_map_server's map_io (loadMapYaml /
// loadMapFromFile), written here on its own as the test's oracle; ReadNav2Map
// loads what map_server loads; tiles carry a map's walls and free space, and
// rasterising them gives the map back.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <unistd.h>

#include <gtest/gtest.h>

#include "core/align/prepared_map.h"
#include "core/grid/map_tiles.h"
#include "core/io/nav2_map.h"
#include "core/localmap/pose_ops.h"

namespace lmd::testing {
namespace {

namespace fs = std::filesystem;

// A file in this test binary's own temporary folder (removed at exit).
std::string TempPath(const std::string& name) {
  struct Folder {
    fs::path dir = fs::temp_directory_path() / ("lmd_nav2_test_" + std::to_string(::getpid()));
    Folder() { fs::create_directories(dir); }
    ~Folder() { fs::remove_all(dir); }
  };
  static const Folder folder;
  return (folder.dir / name).string();
}

// What nav2_map_server does with a map YAML: keys read, image relative to
// the YAML, shade = pixel / 255, occ = 1 - shade (negate 0), trinary
// thresholds, image rows flipped. PGM P5, 8 bit only (what WriteNav2Map writes).
struct Nav2Loaded {
  double resolution = 0, origin[3] = {0, 0, 0}, occupied = 0, free = 0;
  std::string mode;
  int width = 0, height = 0;
  std::vector<int> cells;  // bottom row first
};
Nav2Loaded LoadLikeMapServer(const std::string& yaml_path) {
  Nav2Loaded m;
  std::ifstream yaml(yaml_path);
  std::map<std::string, std::string> keys;
  for (std::string line; std::getline(yaml, line);) {
    const size_t colon = line.find(':');
    if (colon != std::string::npos) keys[line.substr(0, colon)] = line.substr(colon + 2);
  }
  m.resolution = std::stod(keys.at("resolution"));
  m.occupied = std::stod(keys.at("occupied_thresh"));
  m.free = std::stod(keys.at("free_thresh"));
  m.mode = keys.at("mode");
  EXPECT_EQ(keys.at("negate"), "0");
  std::sscanf(keys.at("origin").c_str(), "[%lf, %lf, %lf]", &m.origin[0], &m.origin[1], &m.origin[2]);
  const std::string image = fs::path(yaml_path).parent_path().string() + "/" + keys.at("image");
  std::ifstream pgm(image, std::ios::binary);
  std::string magic, comment;
  int maxval = 0;
  pgm >> magic;
  pgm.ignore(1);
  if (pgm.peek() == '#') std::getline(pgm, comment);
  pgm >> m.width >> m.height >> maxval;
  pgm.ignore(1);
  EXPECT_EQ(magic, "P5");
  EXPECT_EQ(maxval, 255);
  std::vector<unsigned char> pixels(static_cast<size_t>(m.width) * m.height);
  pgm.read(reinterpret_cast<char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
  EXPECT_TRUE(pgm.good());
  m.cells.resize(pixels.size());
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const double occ = 1.0 - pixels[static_cast<size_t>(y) * m.width + x] / 255.0;
      const int cell = m.occupied < occ ? 100 : occ < m.free ? 0 : -1;
      m.cells[static_cast<size_t>(m.height - y - 1) * m.width + x] = cell;
    }
  }
  return m;
}

// A 16 m x 11 m room (0.05 m cells) with an inner wall, unknown outside.
OccupancyMap Room() {
  OccupancyMap map;
  map.resolution = 0.05;
  map.origin = {-3.0, -2.0, 0.0};
  map.width = 360, map.height = 260;
  map.cells.assign(static_cast<size_t>(map.width) * map.height, OccupancyMap::kUnknown);
  for (int y = 20; y < 240; ++y) {
    for (int x = 20; x < 340; ++x) {
      const bool wall = x == 20 || x == 339 || y == 20 || y == 239 || (x == 180 && y < 160);
      map.cells[static_cast<size_t>(y) * map.width + x] = wall ? OccupancyMap::kOccupied : OccupancyMap::kFree;
    }
  }
  return map;
}

TEST(Nav2MapTest, AnExportedMapLoadsInMapServersWayWithItsCellsOriginAndThresholds) {
  const OccupancyMap room = Room();
  const std::string yaml = TempPath("room.yaml");
  ASSERT_TRUE(WriteNav2Map(yaml, room).ok());
  const Nav2Loaded loaded = LoadLikeMapServer(yaml);
  EXPECT_EQ(loaded.mode, "trinary");
  EXPECT_DOUBLE_EQ(loaded.resolution, 0.05);
  EXPECT_DOUBLE_EQ(loaded.origin[0], -3.0);
  EXPECT_DOUBLE_EQ(loaded.origin[1], -2.0);
  ASSERT_EQ(loaded.width, room.width);
  ASSERT_EQ(loaded.height, room.height);
  for (size_t i = 0; i < room.cells.size(); ++i) ASSERT_EQ(loaded.cells[i], room.cells[i]) << "cell " << i;
  // And our reader agrees.
  Result<OccupancyMap> back = ReadNav2Map(yaml);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->cells, room.cells);
}

TEST(Nav2MapTest, ReadingFollowsMapServersNegateScaleAndTextPgm) {
  const std::string pgm = TempPath("tiny.pgm");
  std::ofstream(pgm) << "P2\n# a comment\n3 2\n255\n0 254 205\n100 255 128\n";
  std::ofstream(TempPath("tiny.yaml")) << "image: tiny.pgm\nresolution: 0.1\norigin: [1.0, 2.0, 0.0]\n"
                                          "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  Result<OccupancyMap> map = ReadNav2Map(TempPath("tiny.yaml"));
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  // Image top row = map row 1. 100/255 -> occ 0.61: unknown; 128 -> 0.498 unknown.
  EXPECT_EQ(std::vector<int8_t>(map->cells.begin(), map->cells.end()),
            (std::vector<int8_t>{-1, 0, -1, 100, 0, -1}));
  std::ofstream(TempPath("neg.yaml")) << "image: tiny.pgm\nmode: scale\nresolution: 0.1\norigin: [0, 0, 0]\n"
                                         "negate: 1\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  map = ReadNav2Map(TempPath("neg.yaml"));
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  // negate: occ = shade. 100 -> 0.39 -> scale (0.39-0.196)/(0.65-0.196)*100 = 43.
  EXPECT_EQ(map->cells[0], 43);
  EXPECT_EQ(map->cells[3], 0);    // pixel 0: free when negated
  EXPECT_EQ(map->cells[4], 100);  // pixel 254
}

TEST(Nav2MapTest, BadMapFilesAreRefusedNamingTheFileAndWhatIsWrong) {
  std::ofstream(TempPath("nokey.yaml")) << "image: tiny.pgm\nresolution: 0.1\n";
  Result<OccupancyMap> r = ReadNav2Map(TempPath("nokey.yaml"));
  EXPECT_NE(r.status().message().find("nokey.yaml: no 'origin' key"), std::string::npos) << r.status().message();
  std::ofstream(TempPath("png.png"), std::ios::binary) << "\x89PNG\r\n\x1a\nrest";
  std::ofstream(TempPath("png.yaml")) << "image: png.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
                                         "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  r = ReadNav2Map(TempPath("png.yaml"));
  EXPECT_NE(r.status().message().find("png.png: not a PGM image"), std::string::npos) << r.status().message();
  std::ofstream(TempPath("cut.pgm"), std::ios::binary) << "P5\n100 100\n255\n" << std::string(50, '\0');
  std::ofstream(TempPath("cut.yaml")) << "image: cut.pgm\nresolution: 0.1\norigin: [0, 0]\nnegate: 0\n"
                                         "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  r = ReadNav2Map(TempPath("cut.yaml"));
  EXPECT_NE(r.status().message().find("'origin' is not what map_server expects"), std::string::npos)
      << r.status().message();
  std::ofstream(TempPath("cut.yaml")) << "image: cut.pgm\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 0\n"
                                         "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  r = ReadNav2Map(TempPath("cut.yaml"));
  EXPECT_NE(r.status().message().find("cut.pgm: PGM is cut short: 10000 pixels declared, 50 present"),
            std::string::npos)
      << r.status().message();
}

TEST(Nav2MapTest, TilesCarryTheWallsAsPointsAndTheFreeCellsAsFreeSpace) {
  const OccupancyMap room = Room();
  const std::vector<MapTile> tiles = TilesFromOccupancyMap(room);
  ASSERT_GE(tiles.size(), 4u);
  for (const MapTile& tile : tiles) {
    ASSERT_GE(tile.map.points.size(), 20u);
    ASSERT_FALSE(tile.map.scans.empty());
    const PreparedMap prepared = PrepareMap(tile.map);
    const Pose2 to_tile = Inverse(tile.frame);
    size_t free_checked = 0, free_seen = 0, unknown_seen_free = 0;
    for (int iy = 0; iy < room.height; iy += 7) {
      for (int ix = 0; ix < room.width; ix += 7) {
        const Point2 p = TransformPoint(to_tile, room.CellCentre(ix, iy));
        if (std::abs(p.x) > 5 || std::abs(p.y) > 5) continue;  // inside the tile
        if (room.at(ix, iy) == OccupancyMap::kFree) {
          ++free_checked;
          free_seen += InFreeSpace(prepared, p);
        } else if (room.at(ix, iy) == OccupancyMap::kUnknown) {
          unknown_seen_free += InFreeSpace(prepared, p);
        }
      }
    }
    EXPECT_GT(free_seen, free_checked * 9 / 10) << tile.map.id;
    EXPECT_EQ(unknown_seen_free, 0u) << tile.map.id;
  }
}

TEST(Nav2MapTest, RasterisingTheTilesGivesTheMapBack) {
  const OccupancyMap room = Room();
  const std::vector<MapTile> tiles = TilesFromOccupancyMap(room);
  std::vector<LocalMap> maps;
  std::vector<Pose2> frames;
  for (const MapTile& t : tiles) maps.push_back(t.map), frames.push_back(t.frame);
  const OccupancyMap back = RasterizeLocalMaps(maps, frames, room.resolution);
  size_t walls = 0, walls_found = 0, free = 0, free_found = 0;
  for (int iy = 0; iy < room.height; ++iy) {
    for (int ix = 0; ix < room.width; ++ix) {
      const Point2 c = room.CellCentre(ix, iy);
      const int bx = static_cast<int>(std::floor((c.x - back.origin.x) / back.resolution));
      const int by = static_cast<int>(std::floor((c.y - back.origin.y) / back.resolution));
      auto back_at = [&](int x, int y) {
        return x >= 0 && y >= 0 && x < back.width && y < back.height ? back.at(x, y) : OccupancyMap::kUnknown;
      };
      if (room.at(ix, iy) == OccupancyMap::kOccupied) {  // a wall within one cell (points kept one per 0.1 m)
        ++walls;
        bool near = false;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) near = near || back_at(bx + dx, by + dy) == OccupancyMap::kOccupied;
        }
        walls_found += near;
      } else if (room.at(ix, iy) == OccupancyMap::kFree) {
        ++free;
        free_found += back_at(bx, by) == OccupancyMap::kFree;
      }
    }
  }
  EXPECT_GT(walls_found, walls * 98 / 100) << walls_found << " of " << walls;
  EXPECT_GT(free_found, free * 95 / 100) << free_found << " of " << free;
}

}  // namespace
}  // namespace lmd::testing
