// libFuzzer target: the MCAP reader (summary or linear scan) and the decoders.
#include "bench/fuzz/fuzz_common.h"
#include "core/io/byte_source.h"
#include "core/io/mcap_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto bag = lmd::OpenMcap(lmd::MemorySource(std::string(reinterpret_cast<const char*>(data), size), "fuzz.mcap"),
                           lmd::fuzz::Options());
  if (bag.ok()) lmd::fuzz::ReadEverything(**bag);
  return 0;
}
