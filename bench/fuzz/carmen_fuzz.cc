// libFuzzer target: the CARMEN log parser.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/carmen_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  lmd::ParseCarmenText(std::string(reinterpret_cast<const char*>(data), size), "fuzz.log");
  return 0;
}
