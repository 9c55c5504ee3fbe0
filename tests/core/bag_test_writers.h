// Writers of small bags for the tests, one per container (MCAP through the
// product's McapWriter; ROS 1 bag v2.0 and rosbag2 SQLite here), covering the
// variants the readers must handle. A TestBag holds serialised messages;
// BagFromLog turns a laser log into LaserScan + Odometry + tf messages.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/io/bag.h"
#include "core/io/compression.h"
#include "core/io/laser_log.h"
#include "core/io/mcap_writer.h"
#include "core/io/ros_messages.h"
#include "core/status.h"

namespace lmd::testing {

struct TestTopic {
  std::string name;
  std::string type;  // ROS 2 spelling, "sensor_msgs/msg/LaserScan"; ROS 1 writers drop "/msg"
};

struct TestMessage {
  size_t topic = 0;
  int64_t time_ns = 0;
  std::string data;
};

struct TestBag {
  MessageEncoding encoding = MessageEncoding::kCdr;
  std::vector<TestTopic> topics;
  std::vector<TestMessage> messages;  // in recording order
  size_t AddTopic(const std::string& name, const std::string& type);
};

// Message encoders, CDR or ROS 1 (the inverse of ros_messages.h).
std::string EncodeLaserScan(const LaserScanMessage& m, MessageEncoding encoding);
std::string EncodeOdometry(const OdometryMessage& m, MessageEncoding encoding);
std::string EncodeTf(const TfMessage& m, MessageEncoding encoding);

struct LogBagOptions {
  bool odometry = true;   // /odom: base_link in odom
  bool tf = false;        // /tf: odom -> base_link (the same poses), and map -> odom if map_offset is set
  bool tf_static = true;  // /tf_static: base_link -> laser (mount)
  Pose2 mount;            // laser in base_link
  bool map_frame = false; // /tf also holds map -> odom = map_offset (a SLAM correction)
  Pose2 map_offset;
  int64_t start_ns = 1000000000;  // stamp of scan 0
  int64_t period_ns = 100000000;  // between scans
};

// Scans of `log` as /scan (frame "laser"), with the poses as the options say:
// base pose = laser pose * inverse(mount); with map_frame, odom poses are
// the laser poses moved by inverse(map_offset) so that map -> laser gives them back.
TestBag BagFromLog(const LaserLog& log, MessageEncoding encoding, const LogBagOptions& options = {});

std::string McapBytes(const TestBag& bag, const McapWriteOptions& options = {});

struct Ros1WriteOptions {
  Compression compression = Compression::kNone;  // kNone, kLz4Frame or kBz2
  size_t chunk_bytes = 64 << 10;
  bool indexed = true;              // false: index_pos 0 and no index section (a recorder that died)
  bool split_connections = false;   // every other message of topic 0 under a second connection id
  bool wrong_index_length = false;  // index-data records declare 4 bytes more than they hold
};
std::string Ros1BagBytes(const TestBag& bag, const Ros1WriteOptions& options = {});

// A rosbag2 SQLite3 .db3 at `path` (Humble's schema, or Foxy's older topics table).
Status WriteRosbag2Sqlite(const TestBag& bag, const std::string& path, bool foxy_schema = false);

}  // namespace lmd::testing
