// Bag readers and laser logs from bags: every container variant written by
// the test writers (bag_test_writers.h) reads back the scans and poses of the
// log it was written from, and gives the same local maps as the CARMEN path.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <map>

#include <gtest/gtest.h>

#include "core/align/scan_odometry.h"
#include "core/io/bag.h"
#include "core/io/bag_log.h"
#include "core/io/byte_source.h"
#include "core/io/carmen_reader.h"
#include "core/io/carmen_writer.h"
#include "core/io/mcap_reader.h"
#include "core/io/ros_messages.h"
#include "core/io/ros1_bag_reader.h"
#include "core/localmap/local_map_builder.h"
#include "core/localmap/pose_ops.h"
#include "core/sim/laser.h"
#include "core/sim/simulate.h"
#include "core/sim/world.h"
#include "tests/core/bag_test_writers.h"

namespace lmd::testing {
namespace {

namespace fs = std::filesystem;

class TempFolder {
 public:
  TempFolder() {
    path_ = (fs::temp_directory_path() / ("lmd_bag_test_" + std::to_string(::getpid()) + "_" +
                                          std::to_string(counter_++)))
                .string();
    fs::create_directories(path_);
  }
  ~TempFolder() { fs::remove_all(path_); }
  std::string File(const std::string& name) const { return path_ + "/" + name; }
  const std::string& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  std::string path_;
};

void Save(const std::string& path, const std::string& bytes) { ASSERT_TRUE(WriteBytesToFile(path, bytes).ok()); }

// The demo robot's first 150 scans after a trip through a CARMEN file (so
// that both paths see the same rounded numbers).
const LaserLog& ShortLog() {
  static const LaserLog log = [] {
    LaserLog sim = DefaultDemoLog();
    sim.scans.resize(std::min<size_t>(sim.scans.size(), 150));
    std::stringstream text;
    EXPECT_TRUE(WriteCarmenLog(text, sim).ok());
    Result<LaserLog> back = ParseCarmenText(text.str(), "short.log");
    EXPECT_TRUE(back.ok()) << back.status().ToString();
    return back.value();
  }();
  return log;
}

void ExpectSameLog(const LaserLog& expected, const LaserLog& got, double pose_tol = 1e-9) {
  ASSERT_EQ(expected.scans.size(), got.scans.size());
  for (size_t i = 0; i < expected.scans.size(); ++i) {
    const Scan &a = expected.scans[i], &b = got.scans[i];
    ASSERT_NEAR(a.pose.x, b.pose.x, pose_tol) << "scan " << i;
    ASSERT_NEAR(a.pose.y, b.pose.y, pose_tol) << "scan " << i;
    ASSERT_NEAR(NormalizeAngle(a.pose.theta - b.pose.theta), 0.0, pose_tol) << "scan " << i;
    ASSERT_FLOAT_EQ(a.first_angle, b.first_angle);
    ASSERT_FLOAT_EQ(a.angle_step, b.angle_step);
    ASSERT_FLOAT_EQ(a.max_range, b.max_range);
    ASSERT_EQ(a.ranges, b.ranges) << "scan " << i;
  }
}

void ExpectSameMaps(const LaserLog& expected, const LaserLog& got, double tol = 1e-6) {
  const std::vector<LocalMap> a = BuildLocalMaps(expected), b = BuildLocalMaps(got);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 0u);
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].points.size(), b[i].points.size()) << "map " << i;
    for (size_t k = 0; k < a[i].points.size(); ++k) {
      ASSERT_NEAR(a[i].points[k].x, b[i].points[k].x, tol);
      ASSERT_NEAR(a[i].points[k].y, b[i].points[k].y, tol);
    }
  }
}

Result<LaserLog> ReadBytesAsMcap(const std::string& bytes, const BagLogOptions& options = {},
                                 BagLogSummary* summary = nullptr) {
  Result<std::unique_ptr<BagReader>> bag = OpenMcap(MemorySource(bytes, "test.mcap"), options.read);
  if (!bag.ok()) return bag.status();
  return BagLaserLog(**bag, options, summary);
}

Result<LaserLog> ReadBytesAsRos1(const std::string& bytes, const BagLogOptions& options = {},
                                 BagLogSummary* summary = nullptr) {
  Result<std::unique_ptr<BagReader>> bag = OpenRos1Bag(MemorySource(bytes, "test.bag"), options.read);
  if (!bag.ok()) return bag.status();
  return BagLaserLog(**bag, options, summary);
}

// ---------------------------------------------------------------------------
// Every container variant gives the log back.

struct McapVariant {
  const char* name;
  McapWriteOptions options;
};

TEST(BagReaderTest, EveryMcapVariantReadsBackTheLogAndItsMaps) {
  const TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kCdr);
  McapWriteOptions small;
  small.chunk_bytes = 8 << 10;  // several chunks
  std::vector<McapVariant> variants;
  for (Compression c : {Compression::kNone, Compression::kZstd, Compression::kLz4Frame}) {
    McapWriteOptions o = small;
    o.compression = c;
    variants.push_back({CompressionName(c), o});
    o.summary = false;
    variants.push_back({"no summary", o});
  }
  McapWriteOptions loose;
  loose.chunked = false;
  variants.push_back({"unchunked", loose});
  loose.summary = false;
  variants.push_back({"unchunked, no summary", loose});
  McapWriteOptions no_crc = small;
  no_crc.crcs = false;
  variants.push_back({"no CRCs", no_crc});
  for (const McapVariant& v : variants) {
    SCOPED_TRACE(v.name);
    BagLogSummary summary;
    Result<LaserLog> log = ReadBytesAsMcap(McapBytes(bag, v.options), {}, &summary);
    ASSERT_TRUE(log.ok()) << log.status().ToString();
    ExpectSameLog(ShortLog(), *log);
    EXPECT_EQ(summary.pose_source, "odometry /odom (odom -> base_link)");
  }
  ExpectSameMaps(ShortLog(), *ReadBytesAsMcap(McapBytes(bag, small)));
}

TEST(BagReaderTest, AnMcapCutAfterItsLastChunkIsScannedLikeACrashedRecordersFile) {
  McapWriteOptions o;
  o.chunk_bytes = 8 << 10;
  o.summary = false;
  std::string bytes = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), o);
  // Drop DataEnd, footer and magic (9 + 4, 9 + 20, 8 bytes): what a killed recorder leaves.
  bytes.resize(bytes.size() - 13 - 29 - 8);
  Result<LaserLog> log = ReadBytesAsMcap(bytes);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ExpectSameLog(ShortLog(), *log);
}

// A salvaged read of ShortLog's bag cut in half: its first scans, more
// than 10 and fewer than all.
void ExpectTheLogsHead(const Result<LaserLog>& log) {
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ASSERT_GT(log->scans.size(), 10u);
  ASSERT_LT(log->scans.size(), ShortLog().scans.size());
  LaserLog head = ShortLog();
  head.scans.resize(log->scans.size());
  ExpectSameLog(head, *log);
}

TEST(BagReaderTest, SalvageReadsTheCompleteChunksOfAFileCutInsideOne) {
  McapWriteOptions o;
  o.chunk_bytes = 8 << 10;
  const std::string full = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), o);
  const std::string cut = full.substr(0, full.size() / 2);
  EXPECT_FALSE(ReadBytesAsMcap(cut).ok());
  BagLogOptions salvage;
  salvage.read.salvage_truncated = true;
  ExpectTheLogsHead(ReadBytesAsMcap(cut, salvage));
}

// intel.mcap cut at 800 KB ends inside its first chunk (uncompressed, 1 MB):
// salvage once found no channel there and said "no sensor_msgs/LaserScan
// topic; the bag's 0 topics". The complete records before the cut are read.
TEST(BagReaderTest, SalvageReadsTheCompleteRecordsOfTheUncompressedChunkACutFallsIn) {
  const std::string full = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr));  // one uncompressed chunk
  const std::string cut = full.substr(0, full.size() / 2);
  BagLogOptions salvage;
  salvage.read.salvage_truncated = true;
  BagLogSummary summary;
  Result<LaserLog> log = ReadBytesAsMcap(cut, salvage, &summary);
  ExpectTheLogsHead(log);
  EXPECT_NE(summary.format.find("cut short in the record at offset "), std::string::npos) << summary.format;
}

// A compressed chunk cannot be read in part: when the cut leaves nothing
// before it, salvage says so instead of listing the bag's 0 topics.
TEST(BagReaderTest, SalvageThatRecoversNothingSaysTheFileIsCut) {
  McapWriteOptions zstd;
  zstd.compression = Compression::kZstd;
  const std::string full = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), zstd);
  BagLogOptions salvage;
  salvage.read.salvage_truncated = true;
  Result<LaserLog> log = ReadBytesAsMcap(full.substr(0, full.size() / 2), salvage);
  ASSERT_FALSE(log.ok());
  const std::string message = log.status().message();
  EXPECT_EQ(log.status().code(), Status::Code::kCorruption) << message;
  EXPECT_EQ(message.rfind("test.mcap: offset ", 0), 0u) << message;
  EXPECT_NE(message.find(": truncated (file cut short?): no complete channel record before the cut, so nothing could "
                         "be salvaged"),
            std::string::npos)
      << message;
}

TEST(BagReaderTest, EveryRos1BagVariantReadsBackTheLog) {
  const TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kRos1);
  struct Variant {
    const char* name;
    Ros1WriteOptions options;
  };
  std::vector<Variant> variants;
  for (Compression c : {Compression::kNone, Compression::kLz4Frame, Compression::kBz2}) {
    Ros1WriteOptions o;
    o.compression = c;
    variants.push_back({CompressionName(c), o});
    o.indexed = false;
    variants.push_back({"unindexed", o});
  }
  Ros1WriteOptions split;
  split.split_connections = true;
  variants.push_back({"one topic under two connections", split});
  Ros1WriteOptions wrong;
  wrong.wrong_index_length = true;
  variants.push_back({"index data with a wrong length", wrong});
  wrong.indexed = false;
  variants.push_back({"unindexed, index data with a wrong length", wrong});
  for (const Variant& v : variants) {
    SCOPED_TRACE(v.name);
    Result<std::unique_ptr<BagReader>> reader = OpenRos1Bag(MemorySource(Ros1BagBytes(bag, v.options), "t.bag"));
    ASSERT_TRUE(reader.ok()) << reader.status().ToString();
    ASSERT_EQ((*reader)->topics().size(), 3u);  // /scan, /odom, /tf_static: connections grouped by topic
    EXPECT_EQ((*reader)->topics()[0].message_count, ShortLog().scans.size());
    Result<LaserLog> log = BagLaserLog(**reader);
    ASSERT_TRUE(log.ok()) << log.status().ToString();
    ExpectSameLog(ShortLog(), *log);
  }
}

// A finished ROS 1 bag cut short keeps a bag header whose index_pos lies
// beyond the cut: salvage once refused it like any damaged header; it walks
// the records before the cut, and says so when they hold nothing.
TEST(BagReaderTest, SalvageWalksARos1BagWhoseIndexIsCutOff) {
  const std::string full = Ros1BagBytes(BagFromLog(ShortLog(), MessageEncoding::kRos1));
  const std::string cut = full.substr(0, full.size() / 2);
  Result<LaserLog> refused = ReadBytesAsRos1(cut);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("lies outside the file (file cut short?)"), std::string::npos)
      << refused.status().message();
  BagLogOptions salvage;
  salvage.read.salvage_truncated = true;
  BagLogSummary summary;
  Result<LaserLog> log = ReadBytesAsRos1(cut, salvage, &summary);
  ExpectTheLogsHead(log);
  EXPECT_NE(summary.format.find("cut short in the record at offset "), std::string::npos) << summary.format;

  Result<LaserLog> nothing = ReadBytesAsRos1(full.substr(0, 5000), salvage);  // inside the first chunk
  ASSERT_FALSE(nothing.ok());
  EXPECT_EQ(nothing.status().code(), Status::Code::kCorruption);
  EXPECT_NE(nothing.status().message().find("no complete connection record before the cut, so nothing could be "
                                            "salvaged"),
            std::string::npos)
      << nothing.status().message();
}

TEST(BagReaderTest, Rosbag2SqliteFilesAndDirectoriesReadBackTheLog) {
  TempFolder dir;
  const TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kCdr);
  for (bool foxy : {false, true}) {
    const std::string db = dir.File(foxy ? "foxy.db3" : "humble.db3");
    ASSERT_TRUE(WriteRosbag2Sqlite(bag, db, foxy).ok());
    Result<LaserLog> log = ReadBagLaserLog(db);
    ASSERT_TRUE(log.ok()) << log.status().ToString();
    ExpectSameLog(ShortLog(), *log);
  }
  // A bag directory split in two files (rosbag2's --max-bag-size), listed by metadata.yaml.
  const std::string split = dir.File("split");
  fs::create_directories(split);
  TestBag first = bag, second = bag;
  first.messages.resize(bag.messages.size() / 2);
  second.messages.erase(second.messages.begin(), second.messages.begin() + bag.messages.size() / 2);
  ASSERT_TRUE(WriteRosbag2Sqlite(first, split + "/split_0.db3").ok());
  Save(split + "/split_1.mcap", McapBytes(second));
  std::ofstream(split + "/metadata.yaml") << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
                                             "  relative_file_paths:\n  - split_0.db3\n  - split_1.mcap\n"
                                             "  compression_format: ''\n";
  BagLogSummary summary;
  Result<LaserLog> log = ReadBagLaserLog(split, {}, &summary);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ExpectSameLog(ShortLog(), *log);
  EXPECT_NE(summary.format.find("rosbag2 directory of 2 files"), std::string::npos) << summary.format;
}

// ---------------------------------------------------------------------------
// Pose sources.

TEST(BagLogTest, TheLaserMountingFromTfStaticIsComposedWithOdometry) {
  LogBagOptions o;
  o.mount = {0.25, -0.1, 0.3};
  BagLogSummary summary;
  Result<LaserLog> log = ReadBytesAsMcap(McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr, o)), {}, &summary);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  ExpectSameLog(ShortLog(), *log, 1e-7);
  EXPECT_EQ(summary.laser_mounting, "base_link -> laser from tf: (0.250 m, -0.100 m, 17.2 deg)");
}

TEST(BagLogTest, ASlamPoseInTfWinsOverOdometryAndFrameChoosesTheFrame) {
  LogBagOptions o;
  o.tf = true;
  o.map_frame = true;
  o.map_offset = {3.0, -2.0, 0.5};
  o.mount = {0.1, 0.0, 0.0};
  const std::string bytes = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr, o));
  BagLogSummary summary;
  Result<LaserLog> log = ReadBytesAsMcap(bytes, {}, &summary);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  EXPECT_EQ(summary.pose_source, "tf map -> laser");
  ExpectSameLog(ShortLog(), *log, 1e-7);
  // In odom the poses differ from the map's by the SLAM correction; odometry gives the same as tf odom.
  BagLogOptions in_odom;
  in_odom.frame = "odom";
  Result<LaserLog> odom = ReadBytesAsMcap(bytes, in_odom, &summary);
  ASSERT_TRUE(odom.ok()) << odom.status().ToString();
  EXPECT_EQ(summary.pose_source, "tf odom -> laser");
  const Pose2 expected = Compose(Inverse(o.map_offset), ShortLog().scans[10].pose);
  EXPECT_NEAR(odom->scans[10].pose.x, expected.x, 1e-7);
  EXPECT_NEAR(odom->scans[10].pose.y, expected.y, 1e-7);
  BagLogOptions by_odometry;
  by_odometry.odom_topic = "/odom";
  Result<LaserLog> odometry = ReadBytesAsMcap(bytes, by_odometry, &summary);
  ASSERT_TRUE(odometry.ok());
  ExpectSameLog(*odom, *odometry, 1e-7);
}

// A 12 m x 9 m room with boxes and a 7 m drive through it, one scan per 0.1 m
// (a corridor would not do: sliding along it fits every scan equally well).
LaserLog RoomDrive() {
  std::vector<Segment> walls = {{{0, 0}, {12, 0}}, {{12, 0}, {12, 9}}, {{12, 9}, {0, 9}}, {{0, 9}, {0, 0}}};
  for (const auto& [x, y, w] : std::vector<std::array<double, 3>>{{3, 2, 0.6}, {8, 6.5, 1.0}, {5, 7, 0.4}, {9.5, 2, 0.8}}) {
    walls.push_back({{x, y}, {x + w, y}}), walls.push_back({{x + w, y}, {x + w, y + w}});
    walls.push_back({{x + w, y + w}, {x, y + w}}), walls.push_back({{x, y + w}, {x, y}});
  }
  const World world(walls, {});
  std::vector<Pose2> route;
  for (int i = 0; i <= 70; ++i) {
    const double a = i * 0.01;  // a gentle left turn
    route.push_back({2 + 10 * std::sin(a + 0.35) - 10 * std::sin(0.35), 3.5 - 10 * std::cos(a + 0.35) + 10 * std::cos(0.35), a});
  }
  return SimulateLog(world, route, LaserOptions{}, /*seed=*/7);
}

TEST(BagLogTest, ABagOfScansAlonePosesThemByScanMatchingAndSaysSo) {
  const LaserLog truth = RoomDrive();
  LogBagOptions o;
  o.odometry = false;
  o.tf_static = false;
  BagLogSummary summary;
  Result<LaserLog> log = ReadBytesAsMcap(McapBytes(BagFromLog(truth, MessageEncoding::kCdr, o)), {}, &summary);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  EXPECT_EQ(summary.pose_source.rfind("scan matching (the bag records no odometry and no tf", 0), 0u)
      << summary.pose_source;
  // After 7 m (more than one local map) the matched pose follows the true one.
  const Pose2 t = Compose(Inverse(truth.scans.front().pose), truth.scans.back().pose);
  const Pose2 m = log->scans.back().pose;
  EXPECT_LT(std::hypot(t.x - m.x, t.y - m.y), 0.10) << m.x << " " << m.y << " vs " << t.x << " " << t.y;
  EXPECT_LT(std::abs(NormalizeAngle(t.theta - m.theta)), 1 * M_PI / 180);
  EXPECT_EQ(BuildLocalMaps(*log).size(), BuildLocalMaps(truth).size());
}

// ---------------------------------------------------------------------------
// Topic choice.

TestBag TwoScanTopics() {
  TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kCdr);
  const size_t second = bag.AddTopic("/scan_rear", "sensor_msgs/msg/LaserScan");
  bag.messages.push_back({second, 1000000000, bag.messages[2].data});
  return bag;
}

TEST(BagLogTest, TwoScanTopicsAreRefusedListingBothUntilOneIsChosen) {
  const std::string bytes = McapBytes(TwoScanTopics());
  Result<LaserLog> log = ReadBytesAsMcap(bytes);
  ASSERT_FALSE(log.ok());
  EXPECT_NE(log.status().message().find("2 sensor_msgs/LaserScan topics, choose one with --scan-topic: "
                                        "/scan (sensor_msgs/msg/LaserScan, 150), /scan_rear (sensor_msgs/msg/LaserScan, 1)"),
            std::string::npos)
      << log.status().message();
  BagLogOptions o;
  o.scan_topic = "/scan";
  EXPECT_TRUE(ReadBytesAsMcap(bytes, o).ok());
  o.scan_topic = "/odom";
  log = ReadBytesAsMcap(bytes, o);
  EXPECT_NE(log.status().message().find("topic /odom is nav_msgs/msg/Odometry, not sensor_msgs/LaserScan"),
            std::string::npos)
      << log.status().message();
  o.scan_topic = "/laser";
  log = ReadBytesAsMcap(bytes, o);
  EXPECT_NE(log.status().message().find("no topic /laser in the bag"), std::string::npos) << log.status().message();
}

// ---------------------------------------------------------------------------
// Bad input: a clear error naming the file, the offset or message, and what is wrong.

std::string ChunkedMcap() {
  McapWriteOptions o;
  o.chunk_bytes = 8 << 10;
  return McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), o);
}

// Offset of the first chunk record's body.
size_t FirstChunkBody(const std::string& mcap) {
  size_t at = 8;
  while (static_cast<uint8_t>(mcap[at]) != 0x06) {
    uint64_t len = 0;
    std::memcpy(&len, mcap.data() + at + 1, 8);
    at += 9 + len;
  }
  return at + 9;
}

std::string Message(const Result<LaserLog>& r) { return r.ok() ? "(ok)" : r.status().message(); }

TEST(BagBadInputTest, McapDamageIsNamedWithItsOffset) {
  const std::string good = ChunkedMcap();
  {  // cut short
    Result<LaserLog> r = ReadBytesAsMcap(good.substr(0, good.size() / 2));
    EXPECT_NE(Message(r).find("test.mcap: offset "), std::string::npos) << Message(r);
    EXPECT_NE(Message(r).find("truncated"), std::string::npos) << Message(r);
  }
  {  // bad magic
    std::string bad = good;
    bad[1] = 'X';
    Result<LaserLog> r = ReadBytesAsMcap(bad);
    EXPECT_EQ(r.status().code(), Status::Code::kInvalidArgument);
    EXPECT_NE(Message(r).find("test.mcap: not an MCAP file (bad magic)"), std::string::npos) << Message(r);
  }
  const size_t body = FirstChunkBody(good);
  {  // a flipped byte in the chunk's records: CRC mismatch
    std::string bad = good;
    bad[body + 8 + 8 + 8 + 4 + 4 + 8 + 100] ^= 0x55;
    Result<LaserLog> r = ReadBytesAsMcap(bad);
    EXPECT_NE(Message(r).find("chunk CRC mismatch"), std::string::npos) << Message(r);
    EXPECT_NE(Message(r).find("offset " + std::to_string(body - 9)), std::string::npos) << Message(r);
  }
  {  // unknown compression: the (empty) compression string becomes "brot"
    McapWriteOptions o;
    o.chunk_bytes = 8 << 10;
    o.compression = Compression::kZstd;
    std::string bad = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), o);
    const size_t name = FirstChunkBody(bad) + 8 + 8 + 8 + 4 + 4;
    ASSERT_EQ(bad.substr(name, 4), "zstd");
    bad.replace(name, 4, "brot");
    Result<LaserLog> r = ReadBytesAsMcap(bad);
    EXPECT_NE(Message(r).find("chunk has unknown compression 'brot' (known: zstd, lz4, none)"), std::string::npos)
        << Message(r);
    // A wrong uncompressed size, compressed and not.
    bad.replace(name, 4, "zstd");
    bad[FirstChunkBody(bad) + 16] ^= 0x01;
    r = ReadBytesAsMcap(bad);
    EXPECT_NE(Message(r).find("zstd data decompresses to"), std::string::npos) << Message(r);
  }
  {
    std::string bad = good;
    bad[body + 16] ^= 0x01;
    Result<LaserLog> r = ReadBytesAsMcap(bad);
    EXPECT_NE(Message(r).find("uncompressed data decompresses to"), std::string::npos) << Message(r);
  }
  {  // the summary's CRC
    std::string bad = good;
    bad[bad.size() - 8 - 4] ^= 0x01;
    Result<LaserLog> r = ReadBytesAsMcap(bad);
    EXPECT_NE(Message(r).find("summary CRC mismatch"), std::string::npos) << Message(r);
  }
}

TEST(BagBadInputTest, McapDataSectionCrcIsCheckedWhenScanned) {
  McapWriteOptions o;
  o.summary = false;
  std::string bad = McapBytes(BagFromLog(ShortLog(), MessageEncoding::kCdr), o);
  bad[bad.size() - 8 - 29 - 4] ^= 0x01;  // DataEnd's CRC
  Result<LaserLog> r = ReadBytesAsMcap(bad);
  EXPECT_NE(Message(r).find("data section CRC mismatch"), std::string::npos) << Message(r);
}

TEST(BagBadInputTest, Ros1BagDamageIsNamed) {
  Ros1WriteOptions o;
  o.compression = Compression::kBz2;
  const std::string good = Ros1BagBytes(BagFromLog(ShortLog(), MessageEncoding::kRos1), o);
  Result<LaserLog> r = ReadBytesAsRos1(good.substr(0, good.size() - 100));
  EXPECT_NE(Message(r).find("test.bag: "), std::string::npos) << Message(r);
  EXPECT_NE(Message(r).find("truncated"), std::string::npos) << Message(r);
  r = ReadBytesAsRos1("#ROSBAG V1.2\n" + good.substr(13));
  EXPECT_NE(Message(r).find("only v2.0 is read"), std::string::npos) << Message(r);
  std::string bad = good;
  const size_t name = bad.find("compression=bz2");
  ASSERT_NE(name, std::string::npos);
  bad.replace(name + 12, 3, "zip");
  r = ReadBytesAsRos1(bad);
  EXPECT_NE(Message(r).find("chunk has unknown compression 'zip' (known: none, lz4, bz2)"), std::string::npos)
      << Message(r);
  bad = good;
  const size_t size = bad.find("size=") + 5;
  bad[size] ^= 0x01;
  r = ReadBytesAsRos1(bad);
  EXPECT_NE(Message(r).find("bz2 data decompresses to"), std::string::npos) << Message(r);
}

TEST(BagBadInputTest, ADamagedSqliteDatabaseIsAnErrorNotACrash) {
  TempFolder dir;
  const std::string db = dir.File("bad.db3");
  ASSERT_TRUE(WriteRosbag2Sqlite(BagFromLog(ShortLog(), MessageEncoding::kCdr), db).ok());
  std::string bytes;
  {
    std::ifstream in(db, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  for (size_t i = 100; i < bytes.size(); i += 97) bytes[i] = static_cast<char>(bytes[i] ^ 0x5a);
  Save(db, bytes);
  Result<LaserLog> r = ReadBagLaserLog(db);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(Message(r).find(db), std::string::npos) << Message(r);
}

TEST(BagBadInputTest, BadScansAndTimesNameTheMessage) {
  LaserLog log = ShortLog();
  {
    TestBag bag = BagFromLog(log, MessageEncoding::kCdr);
    LaserScanMessage m;
    m.frame_id = "laser";
    m.angle_increment = -0.01f;
    m.ranges = {1, 2, 3};
    bag.messages[40].data = EncodeLaserScan(m, MessageEncoding::kCdr);
    ASSERT_EQ(bag.messages[40].topic, 0u);
    Result<LaserLog> r = ReadBytesAsMcap(McapBytes(bag));
    EXPECT_NE(Message(r).find("test.mcap: /scan message 20 (byte "), std::string::npos) << Message(r);
    EXPECT_NE(Message(r).find("angle_increment is -0.010000 rad: it must be a positive number"), std::string::npos)
        << Message(r);
  }
  {
    log.scans[20].ranges[7] = std::nanf("");
    Result<LaserLog> r = ReadBytesAsMcap(McapBytes(BagFromLog(log, MessageEncoding::kCdr)));
    EXPECT_NE(Message(r).find("/scan message 21 "), std::string::npos) << Message(r);
    EXPECT_NE(Message(r).find("range 7 of "), std::string::npos) << Message(r);
    BagLogOptions allow;
    allow.allow_nan_ranges = true;
    Result<LaserLog> read = ReadBytesAsMcap(McapBytes(BagFromLog(log, MessageEncoding::kCdr)), allow);
    ASSERT_TRUE(read.ok());
    EXPECT_EQ(read->scans[20].ranges[7], read->scans[20].max_range);
  }
  {  // a stamp 5 s before the previous scan's
    TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kRos1);
    Result<LaserScanMessage> m = DecodeLaserScan(bag.messages[3 * 30 + 2].data, MessageEncoding::kRos1);
    ASSERT_TRUE(m.ok());
    m->stamp_ns -= 5000000000;
    bag.messages[3 * 30 + 2].data = EncodeLaserScan(*m, MessageEncoding::kRos1);
    Result<LaserLog> r = ReadBytesAsRos1(Ros1BagBytes(bag));
    EXPECT_NE(Message(r).find("test.bag: /scan message 46 "), std::string::npos) << Message(r);
    EXPECT_NE(Message(r).find("time goes backwards"), std::string::npos) << Message(r);
  }
  {  // a message cut short
    TestBag bag = BagFromLog(ShortLog(), MessageEncoding::kCdr);
    ASSERT_EQ(bag.messages[6].topic, 0u);
    bag.messages[6].data.resize(bag.messages[6].data.size() / 2);
    Result<LaserLog> r = ReadBytesAsMcap(McapBytes(bag));
    EXPECT_NE(Message(r).find("sensor_msgs/LaserScan (CDR): ranges: 180 values declared"), std::string::npos)
        << Message(r);
  }
}

// ---------------------------------------------------------------------------
// Real recordings in ../shared/bags (see its README).

std::string BagsDir() { return std::string(LMD_SHARED_DATA_DIR) + "/../bags"; }

#define REQUIRE_BAG(name)                                                                   \
  const std::string path = BagsDir() + "/" + name;                                          \
  if (!fs::exists(path)) GTEST_SKIP() << path << " is absent (../shared/bags not mounted)"

TEST(RealBagTest, IntelMcapGivesTheSameLocalMapsAsTheCarmenLog) {
  REQUIRE_BAG("intel.mcap");
  const std::string carmen = std::string(LMD_SHARED_DATA_DIR) + "/intel.log.gz";
  if (!fs::exists(carmen)) GTEST_SKIP() << carmen << " is absent";
  BagLogSummary summary;
  Result<LaserLog> bag = ReadBagLaserLog(path, {}, &summary);
  ASSERT_TRUE(bag.ok()) << bag.status().ToString();
  EXPECT_EQ(summary.scans_read, 910u);
  EXPECT_EQ(summary.pose_source, "odometry /odom (odom -> base_link)");
  Result<LaserLog> log = ReadCarmenLog(carmen);
  ASSERT_TRUE(log.ok());
  ExpectSameLog(*log, *bag, 1e-9);
  ExpectSameMaps(*log, *bag, 1e-9);
  EXPECT_EQ(BuildLocalMaps(*bag).size(), 492u);
}

TEST(RealBagTest, TheNav2TurtlebotBagHasNoScansAndIsRefusedListingItsTopics) {
  REQUIRE_BAG("evo_nav2_turtlebot.mcap");
  Result<LaserLog> log = ReadBagLaserLog(path);
  ASSERT_FALSE(log.ok());
  EXPECT_EQ(log.status().code(), Status::Code::kInvalidArgument);
  for (const char* topic : {"no sensor_msgs/LaserScan topic", "/odom (nav_msgs/msg/Odometry, 2639)",
                            "/tf (tf2_msgs/msg/TFMessage, 5422)", "/tf_static (tf2_msgs/msg/TFMessage, 1)"}) {
    EXPECT_NE(log.status().message().find(topic), std::string::npos) << log.status().message();
  }
}

TEST(RealBagTest, TheNav2TurtlebotBagsZstdChunksDecodeToItsOdometryAndTf) {
  REQUIRE_BAG("evo_nav2_turtlebot.mcap");
  Result<std::unique_ptr<BagReader>> bag = OpenBag(path);
  ASSERT_TRUE(bag.ok()) << bag.status().ToString();
  std::vector<size_t> wanted;
  for (size_t i = 0; i < (*bag)->topics().size(); ++i) {
    if ((*bag)->topics()[i].name != "/amcl_pose") wanted.push_back(i);
  }
  std::map<std::string, size_t> decoded;
  int64_t last_odom = 0;
  size_t odom_backwards = 0;
  Status read = (*bag)->ReadMessages(wanted, [&](const BagMessage& m) -> Status {
    const BagTopic& topic = (*bag)->topics()[m.topic];
    if (CanonicalType(topic.type) == "nav_msgs/Odometry") {
      Result<OdometryMessage> o = DecodeOdometry(m.data, topic.encoding);
      if (!o.ok()) return o.status();
      odom_backwards += o->stamp_ns < last_odom;
      last_odom = o->stamp_ns;
      if (o->child_frame_id != "base_footprint" && o->child_frame_id != "base_link") {
        return Status::Internal("odometry of " + o->child_frame_id);
      }
    } else {
      Result<TfMessage> t = DecodeTfMessage(m.data, topic.encoding);
      if (!t.ok()) return t.status();
      if (t->transforms.empty()) return Status::Internal("an empty TFMessage");
    }
    ++decoded[topic.name];
    return Status::Ok();
  });
  ASSERT_TRUE(read.ok()) << read.ToString();
  EXPECT_NE((*bag)->format().find("zstd"), std::string::npos) << (*bag)->format();
  EXPECT_EQ(decoded["/odom"], 2639u);
  EXPECT_EQ(decoded["/tf"], 5422u);
  EXPECT_EQ(decoded["/tf_static"], 1u);
  EXPECT_EQ(odom_backwards, 0u);
}

TEST(RealBagTest, TheStageRos1BagGivesItsScansPosedByGroundTruth) {
  REQUIRE_BAG("cupoch_Mapping1.bag");
  BagLogSummary summary;
  Result<LaserLog> log = ReadBagLaserLog(path, {}, &summary);
  ASSERT_TRUE(log.ok()) << log.status().ToString();
  EXPECT_EQ(summary.scans_read, 1727u);
  EXPECT_EQ(log->scans.size(), 1727u);
  EXPECT_EQ(summary.pose_source, "odometry /base_pose_ground_truth (odom -> base_link)");
  EXPECT_NE(summary.format.find("bz2"), std::string::npos) << summary.format;
  EXPECT_EQ(BuildLocalMaps(*log).size(), 74u);
}

// Scan matching against the recorded poses: the pose error at the end of
// each 5 m window (one local map), printed for docs/bags.md. These logs keep
// one scan per 0.5-1 m or 30 deg turned, hard for scan-to-scan matching;
// the settings were chosen on intel, the other logs were not looked at.
struct WindowErrors {
  size_t windows = 0;
  double median_m = 0, p90_m = 0, median_deg = 0, p90_deg = 0;
};
WindowErrors ScanMatchingErrors(const LaserLog& recorded) {
  const ScanOdometry matched = EstimateScanOdometry(recorded.scans);
  const std::vector<double> travel = CumulativeTravel(recorded);
  std::vector<double> metres, degrees;
  for (size_t i = 0; i < recorded.scans.size(); i += 5) {
    size_t j = i;
    while (j + 1 < travel.size() && travel[j] - travel[i] < 5.0) ++j;
    if (travel[j] - travel[i] < 5.0) break;
    const Pose2 t = Compose(Inverse(recorded.scans[i].pose), recorded.scans[j].pose);
    const Pose2 m = Compose(Inverse(matched.poses[i]), matched.poses[j]);
    metres.push_back(std::hypot(t.x - m.x, t.y - m.y));
    degrees.push_back(std::abs(NormalizeAngle(t.theta - m.theta)) * 180 / M_PI);
  }
  std::sort(metres.begin(), metres.end());
  std::sort(degrees.begin(), degrees.end());
  WindowErrors e;
  e.windows = metres.size();
  if (e.windows == 0) return e;
  e.median_m = metres[e.windows / 2], e.p90_m = metres[e.windows * 9 / 10];
  e.median_deg = degrees[e.windows / 2], e.p90_deg = degrees[e.windows * 9 / 10];
  return e;
}

TEST(RealBagTest, ScanMatchedPosesFollowTheRecordedOnesOverMostLocalMaps) {
  REQUIRE_BAG("intel.mcap");
  BagLogOptions o;
  o.scan_matching = true;
  Result<LaserLog> matched = ReadBagLaserLog(path, o);  // the bag path, as lmdctl --scan-matching runs it
  Result<LaserLog> recorded = ReadBagLaserLog(path);
  ASSERT_TRUE(matched.ok() && recorded.ok());
  EXPECT_EQ(matched->scans.size(), recorded->scans.size());
  std::vector<std::pair<std::string, LaserLog>> logs = {{"intel.mcap", *recorded}};
  for (const char* name : {"aces", "fr101", "orebro", "csail", "edmonton"}) {
    Result<LaserLog> log = ReadCarmenLog(std::string(LMD_SHARED_DATA_DIR) + "/" + name + ".log.gz");
    if (log.ok()) logs.emplace_back(std::string(name) + ".log.gz", std::move(log).value());
  }
  for (const auto& [name, log] : logs) {
    const WindowErrors e = ScanMatchingErrors(log);
    std::printf("scan matching %-16s %3zu windows of 5 m: end error median %.3f m, p90 %.3f m; median %.2f deg, "
                "p90 %.2f deg\n", name.c_str(), e.windows, e.median_m, e.p90_m, e.median_deg, e.p90_deg);
    EXPECT_LT(e.median_m, 0.2) << name;
    EXPECT_LT(e.median_deg, 1.5) << name;
  }
}

TEST(RealBagTest, TheRosbagsTestBagsDecodeTheSameInMcapAndSqlite) {
  REQUIRE_BAG("rosbags_rs_mcap");
  const std::string sqlite = BagsDir() + "/rosbags_rs_sqlite3";
  BagLogSummary from_mcap, from_sqlite;
  Result<LaserLog> a = ReadBagLaserLog(path, {}, &from_mcap);
  Result<LaserLog> b = ReadBagLaserLog(sqlite, {}, &from_sqlite);
  ASSERT_TRUE(a.ok()) << a.status().ToString();
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  EXPECT_EQ(a->scans.size(), 2u);
  ExpectSameLog(*a, *b);
  EXPECT_EQ(from_mcap.pose_source, from_sqlite.pose_source);
  EXPECT_EQ(from_mcap.scan_topic, "/test/sensor_msgs/laser_scan");
  // Two scans at one place: no local map (lmdctl says it is shorter than one).
  EXPECT_TRUE(BuildLocalMaps(*a).empty());
}

}  // namespace
}  // namespace lmd::testing
