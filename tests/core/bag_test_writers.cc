#include "tests/core/bag_test_writers.h"

#include <sqlite3.h>

#include <cmath>
#include <map>

#include "core/io/cdr_writer.h"
#include "core/localmap/pose_ops.h"
#include "core/util/byte_codec.h"

namespace lmd::testing {
namespace {

// ROS 1 serialisation: packed little-endian.
class Ros1Writer {
 public:
  void U32(uint32_t v) { PutU32(out_, v); }
  void F32(float v) { PutF32(out_, v); }
  void F64(double v) { PutF64(out_, v); }
  void String(const std::string& s) { U32(static_cast<uint32_t>(s.size())), out_ += s; }
  void Header(int64_t ns, const std::string& frame) {
    U32(0);  // seq
    U32(static_cast<uint32_t>(ns / 1000000000)), U32(static_cast<uint32_t>(ns % 1000000000));
    String(frame);
  }
  const std::string& data() const { return out_; }

 private:
  std::string out_;
};

// Writes with either writer through one interface.
template <typename W>
void Transform(W& w, const Transform3& t) {
  w.F64(t.x), w.F64(t.y), w.F64(t.z), w.F64(t.qx), w.F64(t.qy), w.F64(t.qz), w.F64(t.qw);
}

template <typename W>
std::string ScanBytes(W w, const LaserScanMessage& m) {
  w.Header(m.stamp_ns, m.frame_id);
  for (float f : {m.angle_min, m.angle_max, m.angle_increment, m.time_increment, m.scan_time, m.range_min,
                  m.range_max}) {
    w.F32(f);
  }
  w.U32(static_cast<uint32_t>(m.ranges.size()));
  for (float r : m.ranges) w.F32(r);
  w.U32(0);  // intensities
  return w.data();
}

template <typename W>
std::string Odom(W w, const OdometryMessage& m) {
  w.Header(m.stamp_ns, m.frame_id);
  w.String(m.child_frame_id);
  Transform(w, m.pose);
  for (int i = 0; i < 36; ++i) w.F64(0);  // pose covariance
  for (int i = 0; i < 6 + 36; ++i) w.F64(0);  // twist and its covariance
  return w.data();
}

template <typename W>
std::string Tf(W w, const TfMessage& m) {
  w.U32(static_cast<uint32_t>(m.transforms.size()));
  for (const TransformStampedMessage& t : m.transforms) {
    w.Header(t.stamp_ns, t.frame_id);
    w.String(t.child_frame_id);
    Transform(w, t.transform);
  }
  return w.data();
}

Transform3 FromPose(const Pose2& p) {
  Transform3 t;
  t.x = p.x, t.y = p.y;
  t.qz = std::sin(p.theta / 2), t.qw = std::cos(p.theta / 2);
  return t;
}

std::string Ros1Type(const std::string& type) {
  std::string t = type;
  const size_t msg = t.find("/msg/");
  if (msg != std::string::npos) t.erase(msg, 4);
  return t;
}

// ROS 1 record: header fields, data.
std::string Field(const std::string& name, const std::string& value) {
  std::string f;
  PutU32(f, static_cast<uint32_t>(name.size() + 1 + value.size()));
  return f + name + "=" + value;
}
std::string U32Bytes(uint32_t v) {
  std::string s;
  PutU32(s, v);
  return s;
}
std::string U64Bytes(uint64_t v) {
  std::string s;
  PutU64(s, v);
  return s;
}
std::string TimeBytes(int64_t ns) {
  return U32Bytes(static_cast<uint32_t>(ns / 1000000000)) + U32Bytes(static_cast<uint32_t>(ns % 1000000000));
}
std::string Ros1Record(const std::string& header, const std::string& data) {
  std::string r;
  PutU32(r, static_cast<uint32_t>(header.size()));
  r += header;
  PutU32(r, static_cast<uint32_t>(data.size()));
  return r + data;
}

}  // namespace

size_t TestBag::AddTopic(const std::string& name, const std::string& type) {
  topics.push_back({name, type});
  return topics.size() - 1;
}

std::string EncodeLaserScan(const LaserScanMessage& m, MessageEncoding e) {
  return e == MessageEncoding::kCdr ? ScanBytes(CdrWriter(), m) : ScanBytes(Ros1Writer(), m);
}
std::string EncodeOdometry(const OdometryMessage& m, MessageEncoding e) {
  return e == MessageEncoding::kCdr ? Odom(CdrWriter(), m) : Odom(Ros1Writer(), m);
}
std::string EncodeTf(const TfMessage& m, MessageEncoding e) {
  return e == MessageEncoding::kCdr ? Tf(CdrWriter(), m) : Tf(Ros1Writer(), m);
}

TestBag BagFromLog(const LaserLog& log, MessageEncoding encoding, const LogBagOptions& options) {
  TestBag bag;
  bag.encoding = encoding;
  const size_t scan = bag.AddTopic("/scan", "sensor_msgs/msg/LaserScan");
  const size_t odom = options.odometry ? bag.AddTopic("/odom", "nav_msgs/msg/Odometry") : 0;
  const size_t tf = options.tf ? bag.AddTopic("/tf", "tf2_msgs/msg/TFMessage") : 0;
  if (options.tf_static) {
    const size_t st = bag.AddTopic("/tf_static", "tf2_msgs/msg/TFMessage");
    TfMessage m;
    m.transforms.push_back({options.start_ns, "base_link", "laser", FromPose(options.mount)});
    bag.messages.push_back({st, options.start_ns, EncodeTf(m, encoding)});
  }
  const Pose2 unmount = Inverse(options.mount);
  const Pose2 odom_in_map = options.map_frame ? options.map_offset : Pose2{};
  for (size_t i = 0; i < log.scans.size(); ++i) {
    const Scan& s = log.scans[i];
    const int64_t t = options.start_ns + static_cast<int64_t>(i) * options.period_ns;
    // base in odom such that odom_in_map * base * mount = the laser pose.
    const Pose2 base = Compose(Inverse(odom_in_map), Compose(s.pose, unmount));
    if (options.odometry) {
      OdometryMessage o{t, "odom", "base_link", FromPose(base)};
      bag.messages.push_back({odom, t, EncodeOdometry(o, encoding)});
    }
    if (options.tf) {
      TfMessage m;
      m.transforms.push_back({t, "odom", "base_link", FromPose(base)});
      if (options.map_frame) m.transforms.push_back({t, "map", "odom", FromPose(odom_in_map)});
      bag.messages.push_back({tf, t, EncodeTf(m, encoding)});
    }
    LaserScanMessage m;
    m.stamp_ns = t;
    m.frame_id = "laser";
    m.angle_min = s.first_angle;
    m.angle_increment = s.angle_step;
    m.angle_max = s.first_angle + s.angle_step * static_cast<float>(s.ranges.size() - 1);
    m.range_min = 0.0f;
    m.range_max = s.max_range;
    m.ranges = s.ranges;
    bag.messages.push_back({scan, t, EncodeLaserScan(m, encoding)});
  }
  return bag;
}

std::string McapBytes(const TestBag& bag, const McapWriteOptions& options) {
  McapWriter w(options);
  std::vector<uint16_t> channels;
  std::map<std::string, uint16_t> schemas;
  for (const TestTopic& t : bag.topics) {
    auto it = schemas.find(t.type);
    if (it == schemas.end()) it = schemas.emplace(t.type, w.AddSchema(t.type, "ros2msg", "# test schema")).first;
    channels.push_back(w.AddChannel(it->second, t.name, bag.encoding == MessageEncoding::kCdr ? "cdr" : "ros1"));
  }
  uint32_t seq = 0;
  for (const TestMessage& m : bag.messages) {
    w.AddMessage(channels[m.topic], seq++, static_cast<uint64_t>(m.time_ns), static_cast<uint64_t>(m.time_ns), m.data);
  }
  return w.Finish();
}

std::string Ros1BagBytes(const TestBag& bag, const Ros1WriteOptions& options) {
  // Connection ids: topic i -> i; with split_connections topic 0 also -> topics.size().
  struct Conn {
    uint32_t id;
    size_t topic;
  };
  std::vector<Conn> conns;
  for (size_t i = 0; i < bag.topics.size(); ++i) conns.push_back({static_cast<uint32_t>(i), i});
  if (options.split_connections) conns.push_back({static_cast<uint32_t>(bag.topics.size()), 0});
  auto conn_record = [&](const Conn& c) {
    const TestTopic& t = bag.topics[c.topic];
    const std::string header = Field("op", std::string(1, '\x07')) + Field("conn", U32Bytes(c.id)) + Field("topic", t.name);
    const std::string data = Field("topic", t.name) + Field("type", Ros1Type(t.type)) + Field("md5sum", "*") +
                             Field("message_definition", "# test");
    return Ros1Record(header, data);
  };

  std::string file = "#ROSBAG V2.0\n";
  const size_t bag_header_at = file.size();
  file += std::string(4096, ' ');  // the bag header record, written last
  struct ChunkInfo {
    uint64_t pos;
    int64_t start, end;
    std::map<uint32_t, uint32_t> counts;
  };
  std::vector<ChunkInfo> infos;
  std::string chunk;
  std::map<uint32_t, std::vector<std::pair<int64_t, uint32_t>>> index;  // conn -> (time, offset in chunk)
  ChunkInfo info{};
  std::map<size_t, size_t> seen_per_topic;
  auto flush = [&]() {
    if (chunk.empty()) return;
    std::string compressed;
    Compress(options.compression, chunk, &compressed);
    const char* name = options.compression == Compression::kBz2 ? "bz2"
                       : options.compression == Compression::kLz4Frame ? "lz4" : "none";
    info.pos = file.size();
    file += Ros1Record(Field("op", std::string(1, '\x05')) + Field("compression", name) +
                           Field("size", U32Bytes(static_cast<uint32_t>(chunk.size()))),
                       compressed);
    for (const auto& [conn, entries] : index) {
      std::string data;
      for (const auto& [time, offset] : entries) data += TimeBytes(time) + U32Bytes(offset);
      const std::string header = Field("op", std::string(1, '\x04')) + Field("ver", U32Bytes(1)) +
                                 Field("conn", U32Bytes(conn)) +
                                 Field("count", U32Bytes(static_cast<uint32_t>(entries.size())));
      std::string record = Ros1Record(header, data);
      if (options.wrong_index_length) {  // the data length field claims 4 more bytes than follow
        const size_t len_at = 4 + header.size();
        std::string fixed;
        PutU32(fixed, static_cast<uint32_t>(data.size() + 4));
        record.replace(len_at, 4, fixed);
      }
      file += record;
    }
    infos.push_back(info);
    chunk.clear();
    index.clear();
    info = ChunkInfo{};
  };
  std::map<uint32_t, bool> conn_in_chunk;
  for (const TestMessage& m : bag.messages) {
    uint32_t conn = static_cast<uint32_t>(m.topic);
    if (options.split_connections && m.topic == 0 && (seen_per_topic[0]++ % 2 == 1)) {
      conn = static_cast<uint32_t>(bag.topics.size());
    }
    if (chunk.empty()) conn_in_chunk.clear(), info.start = m.time_ns;
    if (!conn_in_chunk[conn]) {
      for (const Conn& c : conns) {
        if (c.id == conn) chunk += conn_record(c);
      }
      conn_in_chunk[conn] = true;
    }
    index[conn].emplace_back(m.time_ns, static_cast<uint32_t>(chunk.size()));
    chunk += Ros1Record(Field("op", std::string(1, '\x02')) + Field("conn", U32Bytes(conn)) +
                            Field("time", TimeBytes(m.time_ns)),
                        m.data);
    ++info.counts[conn];
    info.end = m.time_ns;
    if (chunk.size() >= options.chunk_bytes) flush();
  }
  flush();
  uint64_t index_pos = 0;
  if (options.indexed) {
    index_pos = file.size();
    for (const Conn& c : conns) file += conn_record(c);
    for (const ChunkInfo& ci : infos) {
      std::string data;
      for (const auto& [conn, n] : ci.counts) data += U32Bytes(conn) + U32Bytes(n);
      file += Ros1Record(Field("op", std::string(1, '\x06')) + Field("ver", U32Bytes(1)) +
                             Field("chunk_pos", U64Bytes(ci.pos)) + Field("start_time", TimeBytes(ci.start)) +
                             Field("end_time", TimeBytes(ci.end)) +
                             Field("count", U32Bytes(static_cast<uint32_t>(ci.counts.size()))),
                         data);
    }
  }
  const std::string header = Field("op", std::string(1, '\x03')) + Field("index_pos", U64Bytes(index_pos)) +
                             Field("conn_count", U32Bytes(static_cast<uint32_t>(conns.size()))) +
                             Field("chunk_count", U32Bytes(static_cast<uint32_t>(infos.size())));
  const size_t padding = 4096 - 8 - header.size();
  file.replace(bag_header_at, 4096, Ros1Record(header, std::string(padding, ' ')));
  return file;
}

Status WriteRosbag2Sqlite(const TestBag& bag, const std::string& path, bool foxy_schema) {
  std::remove(path.c_str());
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) return Status::IoError(path + ": cannot create");
  std::string sql = foxy_schema
                        ? "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
                          "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
                        : "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);"
                          "INSERT INTO schema VALUES (3, 'humble');"
                          "CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, "
                          "metadata TEXT NOT NULL);"
                          "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
                          "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL, "
                          "type_description_hash TEXT NOT NULL);";
  sql += "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, "
         "data BLOB NOT NULL); CREATE INDEX timestamp_idx ON messages (timestamp ASC); BEGIN;";
  Status result;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) result = Status::IoError(sqlite3_errmsg(db));
  for (size_t i = 0; i < bag.topics.size() && result.ok(); ++i) {
    const std::string insert = "INSERT INTO topics VALUES (" + std::to_string(i + 1) + ", '" + bag.topics[i].name +
                               "', '" + bag.topics[i].type + "', 'cdr', ''" + (foxy_schema ? "" : ", ''") + ");";
    if (sqlite3_exec(db, insert.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) result = Status::IoError(sqlite3_errmsg(db));
  }
  sqlite3_stmt* stmt = nullptr;
  if (result.ok() && sqlite3_prepare_v2(db, "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)", -1,
                                        &stmt, nullptr) != SQLITE_OK) {
    result = Status::IoError(sqlite3_errmsg(db));
  }
  for (const TestMessage& m : bag.messages) {
    if (!result.ok()) break;
    sqlite3_bind_int64(stmt, 1, static_cast<int64_t>(m.topic + 1));
    sqlite3_bind_int64(stmt, 2, m.time_ns);
    sqlite3_bind_blob(stmt, 3, m.data.data(), static_cast<int>(m.data.size()), SQLITE_TRANSIENT);
    if (sqlite3_step(stmt) != SQLITE_DONE) result = Status::IoError(sqlite3_errmsg(db));
    sqlite3_reset(stmt);
  }
  sqlite3_finalize(stmt);
  if (result.ok() && sqlite3_exec(db, "COMMIT;", nullptr, nullptr, nullptr) != SQLITE_OK) {
    result = Status::IoError(sqlite3_errmsg(db));
  }
  sqlite3_close(db);
  return result;
}

}  // namespace lmd::testing
