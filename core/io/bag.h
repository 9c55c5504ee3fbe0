// A recorded robot bag, whatever its container (MCAP, rosbag2 SQLite, ROS 1
// bag v2.0): its topics, and its messages as serialised bytes. Decoding the
// bytes is ros_messages.h's job; turning scans and poses into a laser log is
// bag_log.h's.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/status.h"

namespace lmd {

// How a topic's messages are serialised.
enum class MessageEncoding { kCdr, kRos1, kOther };

struct BagTopic {
  std::string name;        // "/scan"
  std::string type;        // as recorded: "sensor_msgs/msg/LaserScan" (ROS 2) or "sensor_msgs/LaserScan" (ROS 1)
  MessageEncoding encoding = MessageEncoding::kOther;
  std::string encoding_name;  // as recorded: "cdr", "ros1", "json", ...
  uint64_t message_count = 0;  // as the file's index or summary says; 0 when it does not say
};

// One message, valid only during the callback that receives it.
struct BagMessage {
  size_t topic = 0;          // index into BagReader::topics()
  int64_t log_time_ns = 0;   // when the recorder received it
  std::string_view data;     // serialised message
  std::string where;         // where it sits, for errors: "offset 1234", "chunk at offset 99", "row 17"
};

struct BagReadOptions {
  // Bytes; a chunk (or one message) that declares more when decompressed is
  // refused as corrupt. Real chunks hold 1-4 MiB (MCAP's and rosbag's defaults).
  uint64_t max_chunk_bytes = 256ull << 20;
  // A file that ends inside a record (a recorder killed mid-write) is an
  // error naming the offset; true reads the complete records before it
  // (MCAP: also those of an uncompressed chunk the cut falls in), and is
  // Corruption still when they hold no topic.
  bool salvage_truncated = false;
};

class BagReader {
 public:
  virtual ~BagReader() = default;
  // The file or directory it reads; errors name it.
  virtual const std::string& path() const = 0;
  // "MCAP (zstd chunks, summary)", "ROS 1 bag v2.0 (bz2 chunks)", "rosbag2 SQLite3".
  virtual std::string format() const = 0;
  // Topics in the file, one per name (ROS 1 connections with the same topic are one).
  virtual const std::vector<BagTopic>& topics() const = 0;
  // Calls `on_message` for every message of the topics whose indices are in
  // `wanted` (others are skipped unread where the format allows), in file
  // order. Stops at, and returns, the first non-OK status of the callback or
  // the first corruption found ("<path>: ... at offset N: what is wrong").
  virtual Status ReadMessages(const std::vector<size_t>& wanted,
                              const std::function<Status(const BagMessage&)>& on_message) = 0;
};

// The topics of a bag as readers collect them from channels (MCAP), connections
// (ROS 1) or files (split rosbag2 bags): one per (name, type).
class TopicTable {
 public:
  // Index of topic (name, type), added if new (its encoding from the name:
  // "cdr", "ros1" or other); `count` messages are added to it.
  size_t Add(const std::string& name, const std::string& type, const std::string& encoding_name, uint64_t count);
  void AddMessages(size_t topic, uint64_t count) { topics_[topic].message_count += count; }
  const std::vector<BagTopic>& topics() const { return topics_; }

 private:
  std::vector<BagTopic> topics_;
  std::map<std::string, size_t> by_key_;
};

// Opens `path`: a directory holding a rosbag2 bag (metadata.yaml and its
// .db3 / .mcap files, or such files alone), or one file recognised by its
// magic bytes (MCAP, ROS 1 bag v2.0, SQLite). NotFound if absent;
// InvalidArgument if the format is not one of those (naming the magic
// found); Corruption if its index or summary is damaged.
Result<std::unique_ptr<BagReader>> OpenBag(const std::string& path, const BagReadOptions& options = {});

// The topic type without ROS 2's "/msg/": "sensor_msgs/LaserScan"; ROS 1's
// old tf type "tf/tfMessage" as "tf2_msgs/TFMessage".
std::string CanonicalType(const std::string& type);

}  // namespace lmd
