// lmdctl with bags: ingest --bag (MCAP, ROS 1, rosbag2) as a user runs it,
// query --bag, the errors of bad bags, and --mcap results read back by our
// reader and by one we did not write (npm's @mcap/core, when installed).
#include <cmath>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "core/io/bag.h"
#include "core/io/carmen_writer.h"
#include "core/io/nav2_map.h"
#include "core/io/mcap_writer.h"
#include "core/sim/simulate.h"
#include "tests/core/bag_test_writers.h"
#include "tests/server/test_server.h"

namespace lmd::testing {
namespace {

namespace fs = std::filesystem;

int Lines(const std::string& text) { return static_cast<int>(std::count(text.begin(), text.end(), '\n')); }

class LmdctlBagTest : public ::testing::Test {
 protected:
  void SetUp() override {
    log_ = DefaultDemoLog();
    log_.scans.resize(std::min<size_t>(log_.scans.size(), 60));  // ~30 m of travel
    ASSERT_TRUE(WriteCarmenLog(dir_.path() + "/robot.log", log_).ok());
    McapWriteOptions o;
    o.compression = Compression::kZstd;
    ASSERT_TRUE(WriteBytesToFile(dir_.path() + "/robot.mcap", McapBytes(BagFromLog(log_, MessageEncoding::kCdr), o)).ok());
    ASSERT_TRUE(WriteBytesToFile(dir_.path() + "/robot.bag", Ros1BagBytes(BagFromLog(log_, MessageEncoding::kRos1))).ok());
  }
  LaserLog log_;
  TempDir dir_;
  TempDir data_;
};

TEST_F(LmdctlBagTest, IngestOfABagPrintsEveryMapAndASummaryLineAndItsMapsAreQueryable) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  CliRun ingest = RunLmdctl(base + "--json ingest --collection fleet --bag " + dir_.path() + "/robot.mcap", dir_);
  ASSERT_EQ(ingest.exit_code, 0) << ingest.err;
  CliRun from_log = RunLmdctl(base + "--json ingest --collection logs --log " + dir_.path() + "/robot.log", dir_);
  ASSERT_EQ(from_log.exit_code, 0) << from_log.err;
  const int maps = Lines(from_log.out);
  ASSERT_GT(maps, 5);
  EXPECT_EQ(Lines(ingest.out), maps + 1);  // the same maps as the log, then the summary
  EXPECT_EQ(ingest.out.rfind("{\"id\":\"robot-0\"", 0), 0u) << ingest.out;
  EXPECT_NE(ingest.out.find("\"pose_source\":\"odometry /odom (odom -"), std::string::npos) << ingest.out;
  EXPECT_NE(ingest.out.find("\"maps\":" + std::to_string(maps) + "}"), std::string::npos) << ingest.out;

  CliRun text = RunLmdctl(base + "ingest --collection ros1 --bag " + dir_.path() + "/robot.bag", dir_);
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("ROS 1 bag v2.0, chunks: none, indexed; scans /scan (60 read, 0 without a pose)"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("ingested " + std::to_string(maps) + " local maps into 'ros1'"), std::string::npos);

  CliRun query = RunLmdctl(base + "--json query --collection fleet --top-k 3 --bag " + dir_.path() +
                               "/robot.bag --map 4", dir_);
  ASSERT_EQ(query.exit_code, 0) << query.err;
  EXPECT_NE(query.out.find("\"map_id\":\"robot-4\""), std::string::npos) << query.out;
}

TEST_F(LmdctlBagTest, ABadBagFailsWithOneLineExitOneAndSaysNothingWasStored) {
  std::string bytes = McapBytes(BagFromLog(log_, MessageEncoding::kCdr));
  bytes.resize(bytes.size() / 2);
  ASSERT_TRUE(WriteBytesToFile(dir_.path() + "/cut.mcap", bytes).ok());
  CliRun run = RunLmdctl("--server 127.0.0.1:1 ingest --collection fleet --bag " + dir_.path() + "/cut.mcap", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(Lines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("cut.mcap: offset "), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("(no map stored)"), std::string::npos) << run.err;
  run = RunLmdctl("query --collection fleet --bag " + dir_.path() + "/cut.mcap --map 0", dir_);
  EXPECT_EQ(run.exit_code, 1) << run.err;  // the file is at fault, not the command line
}

TEST_F(LmdctlBagTest, AnIngestThatLmddRefusesSaysHowManyMapsWereStored) {
  server::ServerConfig config;
  config.max_scans_per_map = 12;  // the first maps fit, later ones (more scans) do not
  TestServer server(data_.path(), config);
  CliRun run = RunLmdctl("--server " + server.address() + " ingest --collection fleet --bag " + dir_.path() +
                             "/robot.mcap", dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(Lines(run.err), 1) << run.err;  // no progress lines before it: stderr is not a terminal
  EXPECT_NE(run.err.find("INVALID_ARGUMENT"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find(" maps were stored before it)"), std::string::npos) << run.err;
}

TEST_F(LmdctlBagTest, TheNav2TurtlebotBagIsRefusedListingItsTopics) {
  const std::string bag = std::string(LMD_SHARED_DATA_DIR) + "/../bags/evo_nav2_turtlebot.mcap";
  if (!fs::exists(bag)) GTEST_SKIP() << bag << " is absent (../shared/bags not mounted)";
  CliRun run = RunLmdctl("--server 127.0.0.1:1 ingest --collection fleet --bag " + bag, dir_);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_EQ(Lines(run.err), 1) << run.err;
  EXPECT_NE(run.err.find("no sensor_msgs/LaserScan topic; the bag's 4 topics: /odom (nav_msgs/msg/Odometry, 2639)"),
            std::string::npos)
      << run.err;
}

// ---------------------------------------------------------------------------
// --mcap results.

TEST_F(LmdctlBagTest, ChangesWritesAnMcapThatAnIndependentReaderDecodes) {
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  ASSERT_EQ(RunLmdctl(base + "ingest --collection fleet --log " + dir_.path() + "/robot.log", dir_).exit_code, 0);
  const std::string out = dir_.path() + "/result.mcap";
  CliRun run = RunLmdctl(base + "changes --collection fleet --top-k 3 --log " + dir_.path() + "/robot.log --map 4 --mcap " + out,
                         dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("wrote " + out), std::string::npos) << run.out;

  // Our reader: the topics and their types.
  Result<std::unique_ptr<BagReader>> bag = OpenBag(out);
  ASSERT_TRUE(bag.ok()) << bag.status().ToString();
  std::map<std::string, std::string> types;
  for (const BagTopic& t : (*bag)->topics()) types[t.name] = t.type;
  EXPECT_EQ(types["/lmd/query"], "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(types["/lmd/query/trajectory"], "nav_msgs/msg/Path");
  EXPECT_EQ(types["/lmd/hit_1"], "sensor_msgs/msg/PointCloud2");
  EXPECT_EQ(types["/lmd/changes"], "visualization_msgs/msg/MarkerArray");
  EXPECT_EQ(types["/tf_static"], "tf2_msgs/msg/TFMessage");

  // An independent reader: @mcap/core with @foxglove's ros2msg parser and CDR decoder.
  const std::string modules = std::string(LMD_MCAP_CHECK_DIR) + "/node_modules/@mcap/core";
  if (std::system("command -v node >/dev/null 2>&1") != 0 || !fs::exists(modules)) {
    GTEST_SKIP() << "node or " << modules << " absent: run scripts/mcap-check-install.sh to check the file with "
                 << "npm's @mcap/core";
  }
  const std::string command = "LMD_MCAP_CHECK_DIR=" + std::string(LMD_MCAP_CHECK_DIR) + " node " +
                              std::string(LMD_SOURCE_DIR) + "/scripts/mcap-check.mjs " + out + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::string json;
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) json.append(buffer, n);
  ASSERT_EQ(pclose(pipe), 0) << json;
  for (const char* expected : {"\"/lmd/query\":{\"schema\":\"sensor_msgs/msg/PointCloud2\",\"encoding\":\"cdr\","
                               "\"messages\":1,\"frame_id\":\"query\"",
                               "\"fields\":\"x,y,z\"", "\"/lmd/query/trajectory\":{\"schema\":\"nav_msgs/msg/Path\"",
                               "\"/lmd/hit_1\":{\"schema\":\"sensor_msgs/msg/PointCloud2\"", "\"frame_id\":\"hit_1\"",
                               "\"/lmd/changes\":{\"schema\":\"visualization_msgs/msg/MarkerArray\"",
                               "\"transforms\":[\"query -> hit_1\"", "\"qos\":\"transient local\""}) {
    EXPECT_NE(json.find(expected), std::string::npos) << expected << "\n" << json;
  }
}

// ---------------------------------------------------------------------------
// Nav2 maps in and out.

TEST_F(LmdctlBagTest, ANav2MapImportedAndExportedKeepsItsWallsAndFrame) {
  OccupancyMap room;  // 16 m x 11 m, walls around, free inside
  room.resolution = 0.05;
  room.origin = {-3.0, -2.0, 0.0};
  room.width = 360, room.height = 260;
  room.cells.assign(static_cast<size_t>(room.width) * room.height, OccupancyMap::kUnknown);
  for (int y = 20; y < 240; ++y) {
    for (int x = 20; x < 340; ++x) {
      const bool wall = x == 20 || x == 339 || y == 20 || y == 239 || (x == 180 && y < 160);
      room.cells[static_cast<size_t>(y) * room.width + x] = wall ? OccupancyMap::kOccupied : OccupancyMap::kFree;
    }
  }
  ASSERT_TRUE(WriteNav2Map(dir_.path() + "/room.yaml", room).ok());
  TestServer server(data_.path());
  const std::string base = "--server " + server.address() + " ";
  CliRun imported = RunLmdctl(base + "--json import-map --collection site --yaml " + dir_.path() + "/room.yaml", dir_);
  ASSERT_EQ(imported.exit_code, 0) << imported.err;
  EXPECT_EQ(imported.out.rfind("{\"id\":\"room-0-0\"", 0), 0u) << imported.out;
  const int tiles = Lines(imported.out);
  EXPECT_GE(tiles, 4);
  CliRun exported = RunLmdctl(base + "export-map --collection site --out " + dir_.path() + "/back.yaml", dir_);
  ASSERT_EQ(exported.exit_code, 0) << exported.err;
  EXPECT_NE(exported.out.find("from " + std::to_string(tiles) + " anchored maps"), std::string::npos) << exported.out;
  Result<OccupancyMap> back = ReadNav2Map(dir_.path() + "/back.yaml");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  // The room's corners in the map frame are walls in the export too (same frame, within a cell).
  for (const auto& [ix, iy] : std::vector<std::pair<int, int>>{{20, 20}, {339, 239}, {180, 100}, {100, 239}}) {
    const Point2 c = room.CellCentre(ix, iy);
    const int bx = static_cast<int>(std::floor((c.x - back->origin.x) / back->resolution));
    const int by = static_cast<int>(std::floor((c.y - back->origin.y) / back->resolution));
    bool wall = false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        wall = wall || (bx + dx >= 0 && by + dy >= 0 && bx + dx < back->width && by + dy < back->height &&
                        back->at(bx + dx, by + dy) == OccupancyMap::kOccupied);
      }
    }
    EXPECT_TRUE(wall) << "cell " << ix << ", " << iy;
  }
  // One stored map in its own frame, and a collection without anchored maps.
  EXPECT_EQ(RunLmdctl(base + "export-map --collection site --id room-0-0 --out " + dir_.path() + "/one.yaml", dir_)
                .exit_code,
            0);
  ASSERT_EQ(RunLmdctl(base + "ingest --collection logs --log " + dir_.path() + "/robot.log", dir_).exit_code, 0);
  CliRun none = RunLmdctl(base + "export-map --collection logs --out " + dir_.path() + "/none.yaml", dir_);
  EXPECT_EQ(none.exit_code, 1);
  EXPECT_NE(none.err.find("collection 'logs' has no anchored maps"), std::string::npos) << none.err;
  ASSERT_EQ(RunLmdctl(base + "ingest --anchor --collection anchored --bag " + dir_.path() + "/robot.mcap", dir_).exit_code, 0);
  EXPECT_EQ(RunLmdctl(base + "export-map --collection anchored --out " + dir_.path() + "/run.yaml", dir_).exit_code, 0);
}

}  // namespace
}  // namespace lmd::testing
