#include "core/io/mcap_writer.h"

#include <zlib.h>

#include <cstdio>
#include <fstream>

#include "core/util/byte_codec.h"

namespace lmd {
namespace {

constexpr char kMagic[] = "\x89MCAP0\r\n";

enum Opcode : uint8_t {
  kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06,
  kMessageIndex = 0x07, kChunkIndex = 0x08, kStatistics = 0x0B, kSummaryOffset = 0x0E, kDataEnd = 0x0F,
};

void PutString(std::string& out, const std::string& s) {
  PutU32(out, static_cast<uint32_t>(s.size()));
  out += s;
}

std::string Record(uint8_t op, const std::string& body) {
  std::string r(1, static_cast<char>(op));
  PutU64(r, body.size());
  return r + body;
}

uint32_t Crc32(const std::string& bytes) {
  return static_cast<uint32_t>(
      ::crc32(0, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

const char* CompressionField(Compression c) {
  return c == Compression::kZstd ? "zstd" : c == Compression::kLz4Frame ? "lz4" : "";
}

}  // namespace

McapWriter::McapWriter(McapWriteOptions options) : options_(std::move(options)) {
  file_.assign(kMagic, 8);
  std::string header;
  PutString(header, options_.profile);
  PutString(header, options_.library);
  file_ += Record(kHeader, header);
}

uint16_t McapWriter::AddSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  const uint16_t id = next_schema_++;
  std::string body;
  PutU16(body, id);
  PutString(body, name);
  PutString(body, encoding);
  PutString(body, data);
  schema_records_.push_back(Record(kSchema, body));
  Emit(kSchema, body);
  return id;
}

uint16_t McapWriter::AddChannel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                const std::map<std::string, std::string>& metadata) {
  const uint16_t id = next_channel_++;
  std::string body, map;
  PutU16(body, id);
  PutU16(body, schema_id);
  PutString(body, topic);
  PutString(body, message_encoding);
  for (const auto& [k, v] : metadata) PutString(map, k), PutString(map, v);
  PutU32(body, static_cast<uint32_t>(map.size()));
  body += map;
  channel_records_.push_back(Record(kChannel, body));
  channel_counts_[id];
  Emit(kChannel, body);
  return id;
}

void McapWriter::AddMessage(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
                            const std::string& data) {
  std::string body;
  PutU16(body, channel_id);
  PutU32(body, sequence);
  PutU64(body, log_time_ns);
  PutU64(body, publish_time_ns);
  body += data;
  if (options_.chunked) {
    if (chunk_.empty() || log_time_ns < chunk_start_) chunk_start_ = log_time_ns;
    if (chunk_.empty() || log_time_ns > chunk_end_) chunk_end_ = log_time_ns;
    chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  }
  Emit(kMessage, body);
  ++message_count_;
  ++channel_counts_[channel_id];
  first_time_ = std::min(first_time_, log_time_ns);
  last_time_ = std::max(last_time_, log_time_ns);
  if (options_.chunked && chunk_.size() >= options_.chunk_bytes) FlushChunk();
}

void McapWriter::Emit(uint8_t op, const std::string& body) {
  (options_.chunked ? chunk_ : file_) += Record(op, body);
}

void McapWriter::FlushChunk() {
  if (chunk_.empty()) return;
  std::string compressed;
  if (!Compress(options_.compression, chunk_, &compressed).ok()) {
    options_.compression = Compression::kNone;  // the libraries cannot fail on valid input; stay readable anyway
    compressed = chunk_;
  }
  const uint64_t chunk_offset = file_.size();
  std::string body;
  PutU64(body, chunk_start_);
  PutU64(body, chunk_end_);
  PutU64(body, chunk_.size());
  PutU32(body, options_.crcs ? Crc32(chunk_) : 0);
  PutString(body, CompressionField(options_.compression));
  PutU64(body, compressed.size());
  body += compressed;
  file_ += Record(kChunk, body);
  const uint64_t chunk_length = file_.size() - chunk_offset;

  std::string offsets;
  const uint64_t indexes_start = file_.size();
  for (const auto& [channel, entries] : chunk_index_) {
    PutU16(offsets, channel);
    PutU64(offsets, file_.size());
    std::string index;
    PutU16(index, channel);
    PutU32(index, static_cast<uint32_t>(entries.size() * 16));
    for (const auto& [time, offset] : entries) PutU64(index, time), PutU64(index, offset);
    file_ += Record(kMessageIndex, index);
  }
  std::string ci;
  PutU64(ci, chunk_start_);
  PutU64(ci, chunk_end_);
  PutU64(ci, chunk_offset);
  PutU64(ci, chunk_length);
  PutU32(ci, static_cast<uint32_t>(offsets.size()));
  ci += offsets;
  PutU64(ci, file_.size() - indexes_start);
  PutString(ci, CompressionField(options_.compression));
  PutU64(ci, compressed.size());
  PutU64(ci, chunk_.size());
  chunk_index_records_.push_back(Record(kChunkIndex, ci));
  ++chunk_count_;
  chunk_.clear();
  chunk_index_.clear();
}

std::string McapWriter::Finish() {
  if (options_.chunked) FlushChunk();
  std::string data_end;
  PutU32(data_end, options_.crcs ? Crc32(file_) : 0);
  file_ += Record(kDataEnd, data_end);

  uint64_t summary_start = 0, summary_offset_start = 0;
  if (options_.summary) {
    summary_start = file_.size();
    std::vector<std::pair<uint8_t, std::pair<uint64_t, uint64_t>>> groups;  // opcode, (start, length)
    auto group = [&](uint8_t op, const std::vector<std::string>& records) {
      if (records.empty()) return;
      const uint64_t start = file_.size();
      for (const std::string& r : records) file_ += r;
      groups.push_back({op, {start, file_.size() - start}});
    };
    group(kSchema, schema_records_);
    group(kChannel, channel_records_);
    std::string stats, counts;
    PutU64(stats, message_count_);
    PutU16(stats, static_cast<uint16_t>(schema_records_.size()));
    PutU32(stats, static_cast<uint32_t>(channel_records_.size()));
    PutU32(stats, 0);  // attachments
    PutU32(stats, 0);  // metadata
    PutU32(stats, chunk_count_);
    PutU64(stats, message_count_ ? first_time_ : 0);
    PutU64(stats, message_count_ ? last_time_ : 0);
    for (const auto& [channel, n] : channel_counts_) PutU16(counts, channel), PutU64(counts, n);
    PutU32(stats, static_cast<uint32_t>(counts.size()));
    stats += counts;
    group(kStatistics, {Record(kStatistics, stats)});
    group(kChunkIndex, chunk_index_records_);
    summary_offset_start = file_.size();
    for (const auto& [op, range] : groups) {
      std::string so(1, static_cast<char>(op));
      PutU64(so, range.first);
      PutU64(so, range.second);
      file_ += Record(kSummaryOffset, so);
    }
  }
  // Footer: opcode, length 20, summary_start, summary_offset_start, then the
  // CRC of the summary section and of the footer up to that field.
  file_.push_back(static_cast<char>(kFooter));
  PutU64(file_, 20);
  PutU64(file_, summary_start);
  PutU64(file_, summary_offset_start);
  uint32_t summary_crc = 0;
  if (options_.summary && options_.crcs) {
    summary_crc = static_cast<uint32_t>(::crc32(0, reinterpret_cast<const Bytef*>(file_.data() + summary_start),
                                                static_cast<uInt>(file_.size() - summary_start)));
  }
  PutU32(file_, summary_crc);
  file_.append(kMagic, 8);
  return std::move(file_);
}

Status WriteBytesToFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) return Status::IoError(path + ": cannot write");
  return Status::Ok();
}

}  // namespace lmd
