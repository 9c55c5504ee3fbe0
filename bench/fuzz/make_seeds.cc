// Writes small valid seed inputs for the fuzz targets into DIR/<target>/:
// every container variant the test writers make, of a 6-scan log, and a few
// CARMEN records. Built and run by scripts/fuzz.sh.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/io/mcap_writer.h"
#include "tests/core/bag_test_writers.h"

using namespace lmd;
using namespace lmd::testing;

namespace {

void Save(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) return std::fprintf(stderr, "usage: make_seeds DIR\n"), 2;
  const std::string dir = argv[1];
  LaserLog log;
  for (int i = 0; i < 6; ++i) {
    Scan s;
    s.pose = {0.3 * i, 0.05 * i, 0.02 * i};
    s.first_angle = static_cast<float>(-M_PI / 2);
    s.angle_step = static_cast<float>(M_PI / 15);
    s.max_range = 30;
    for (int b = 0; b < 16; ++b) s.ranges.push_back(1.0f + 0.1f * b + 0.01f * i);
    log.scans.push_back(s);
  }
  LogBagOptions with_tf;
  with_tf.tf = true;
  with_tf.map_frame = true;
  const TestBag cdr = BagFromLog(log, MessageEncoding::kCdr, with_tf);
  const TestBag ros1 = BagFromLog(log, MessageEncoding::kRos1);
  int n = 0;
  for (Compression c : {Compression::kNone, Compression::kZstd, Compression::kLz4Frame}) {
    for (bool chunked : {true, false}) {
      for (bool summary : {true, false}) {
        McapWriteOptions o;
        o.compression = c;
        o.chunked = chunked;
        o.summary = summary;
        o.chunk_bytes = 1024;
        Save(dir + "/mcap/seed" + std::to_string(n++) + ".mcap", McapBytes(cdr, o));
      }
    }
  }
  n = 0;
  for (Compression c : {Compression::kNone, Compression::kLz4Frame, Compression::kBz2}) {
    for (bool indexed : {true, false}) {
      Ros1WriteOptions o;
      o.compression = c;
      o.indexed = indexed;
      o.chunk_bytes = 1024;
      o.split_connections = n % 2 == 0;
      Save(dir + "/ros1_bag/seed" + std::to_string(n++) + ".bag", Ros1BagBytes(ros1, o));
    }
  }
  if (!WriteRosbag2Sqlite(cdr, dir + "/rosbag2_sqlite/seed0.db3").ok()) return 1;
  if (!WriteRosbag2Sqlite(cdr, dir + "/rosbag2_sqlite/seed1.db3", /*foxy_schema=*/true).ok()) return 1;
  Save(dir + "/carmen/seed0.log", "# c\nFLASER 4 1.0 2.0 3.0 4.0 0.1 0.2 0.3 0.1 0.2 0.3 1.0 host 1.0\n"
                                  "ODOM 0 0 0 0 0 0 1 h 1\nRAWLASER1 0 -1.57 3.14 1.57 30 0.01 0 3 1 2 3 0 1 h 1\n"
                                  "ROBOTLASER1 0 -1.57 3.14 1.57 30 0.01 0 3 1 2 3 0 0 0 0 0 0 0 0 0 0 0 0 1 h 1\n");
  return 0;
}
