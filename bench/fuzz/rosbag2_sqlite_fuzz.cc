// libFuzzer target: the rosbag2 SQLite3 reader on a database image in memory, and the decoders.
#include "bench/fuzz/fuzz_common.h"
#include "core/io/rosbag2_sqlite_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto bag = lmd::OpenRosbag2SqliteBytes(std::string(reinterpret_cast<const char*>(data), size), "fuzz.db3");
  if (bag.ok()) lmd::fuzz::ReadEverything(**bag);
  return 0;
}
