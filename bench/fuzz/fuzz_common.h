// Shared by the libFuzzer targets (scripts/fuzz.sh builds and runs them; the
// main build does not): read every message of every topic and decode it as
// each of the three message types, so that the decoders see what the
// containers deliver, damaged or not.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/io/bag.h"
#include "core/io/ros_messages.h"

namespace lmd::fuzz {

// Bag options for fuzzing: chunks declared larger than 16 MiB are refused,
// so that a decompression bomb costs milliseconds, not the RSS limit.
inline BagReadOptions Options() {
  BagReadOptions o;
  o.max_chunk_bytes = 16 << 20;
  return o;
}

inline void ReadEverything(BagReader& bag) {
  std::vector<size_t> all;
  for (size_t i = 0; i < bag.topics().size(); ++i) all.push_back(i);
  bag.ReadMessages(all, [&](const BagMessage& m) {
    const MessageEncoding e = bag.topics()[m.topic].encoding;
    DecodeLaserScan(m.data, e);
    DecodeOdometry(m.data, e);
    DecodeTfMessage(m.data, e);
    return Status::Ok();
  });
}

}  // namespace lmd::fuzz
