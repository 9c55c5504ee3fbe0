// libFuzzer target: the ROS 1 bag v2.0 reader (indexed or walked) and the decoders.
#include "bench/fuzz/fuzz_common.h"
#include "core/io/byte_source.h"
#include "core/io/ros1_bag_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto bag = lmd::OpenRos1Bag(lmd::MemorySource(std::string(reinterpret_cast<const char*>(data), size), "fuzz.bag"),
                              lmd::fuzz::Options());
  if (bag.ok()) lmd::fuzz::ReadEverything(**bag);
  return 0;
}
