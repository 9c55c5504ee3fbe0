// MCAP writer (spec version 0): schemas, channels and messages into a file
// that Foxglove, Lichtblick, `ros2 bag play` and MCAP libraries open. Chunked
// (with message indexes, chunk indexes and statistics in the summary) or not;
// chunks uncompressed, zstd or lz4; CRCs written. Built in memory: lmd writes
// query results and test bags, megabytes at most.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/io/compression.h"
#include "core/status.h"

namespace lmd {

struct McapWriteOptions {
  std::string profile = "ros2";  // Header.profile
  std::string library = "lmd";   // Header.library
  bool chunked = true;           // messages in chunks (indexed); false: loose records
  // Uncompressed by default: every MCAP reader opens it without a
  // decompression plugin; results are small.
  Compression compression = Compression::kNone;  // kNone, kZstd or kLz4Frame
  uint64_t chunk_bytes = 1 << 20;  // a chunk is closed once its records reach this size
  bool summary = true;             // schemas, channels, statistics, chunk indexes, summary offsets
  bool crcs = true;                // chunk, data section and summary CRCs (0 = not written)
};

class McapWriter {
 public:
  explicit McapWriter(McapWriteOptions options = {});

  // Ids start at 1 (0 means "no schema" to a channel).
  uint16_t AddSchema(const std::string& name, const std::string& encoding, const std::string& data);
  uint16_t AddChannel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                      const std::map<std::string, std::string>& metadata = {});
  void AddMessage(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
                  const std::string& data);
  // The whole file. The writer is spent afterwards.
  std::string Finish();

 private:
  void Emit(uint8_t op, const std::string& body);  // into the current chunk or the file
  void FlushChunk();

  McapWriteOptions options_;
  std::string file_;
  std::string chunk_;  // records of the open chunk
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<uint16_t, std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  // channel -> (log time, offset)
  std::vector<std::string> schema_records_, channel_records_, chunk_index_records_;
  std::map<uint16_t, uint64_t> channel_counts_;
  uint64_t message_count_ = 0, first_time_ = UINT64_MAX, last_time_ = 0;
  uint32_t chunk_count_ = 0;
  uint16_t next_schema_ = 1, next_channel_ = 0;
};

// Writes `bytes` to `path`; IoError naming it on failure.
Status WriteBytesToFile(const std::string& path, const std::string& bytes);

}  // namespace lmd
